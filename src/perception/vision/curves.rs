//! Polylines along simple curves, points about a pixel apart: what the
//! vision tests and benchmarks draw cables along and check paths against.

/// Points along a circular arc, every pixel or so: centre, radius, start
/// and end angle (radians, image coordinates: y down).
pub fn arc_px(centre: [f64; 2], radius_px: f64, from_rad: f64, to_rad: f64) -> Vec<[f64; 2]> {
    let steps = ((to_rad - from_rad).abs() * radius_px).ceil().max(1.0) as usize;
    (0..=steps)
        .map(|i| {
            let t = from_rad + (to_rad - from_rad) * i as f64 / steps as f64;
            [
                centre[0] + radius_px * t.cos(),
                centre[1] + radius_px * t.sin(),
            ]
        })
        .collect()
}

/// Points along a line segment, every pixel or so.
pub fn segment_px(from: [f64; 2], to: [f64; 2]) -> Vec<[f64; 2]> {
    let steps = (to[0] - from[0]).hypot(to[1] - from[1]).ceil().max(1.0) as usize;
    (0..=steps)
        .map(|i| {
            let t = i as f64 / steps as f64;
            [
                from[0] + t * (to[0] - from[0]),
                from[1] + t * (to[1] - from[1]),
            ]
        })
        .collect()
}
