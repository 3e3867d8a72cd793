//! A cable as a shaded tube: the distance of each pixel from the centre
//! line gives the mask (within the radius), the anti-aliased coverage (the
//! last half pixel), the surface normal (a cylinder's, from the offset
//! across it) for diffuse and specular light, and the soft shadow on what
//! lies beneath.

use opencv::core::Vec3f;

use super::{CableSpec, Light};

/// Share of the cable's colour lit by ambient light, and by the light
/// straight on.
const AMBIENT: f64 = 0.3;
const DIFFUSE: f64 = 0.9;
/// How tight the specular highlight is (Blinn–Phong exponent).
const SHININESS: i32 = 24;
/// The shadow lies this many radii away from the light, and fades out
/// over this many radii beyond the cable's own width.
const SHADOW_SHIFT_RADII: f64 = 0.7;
pub(super) const SHADOW_SOFTNESS_RADII: f64 = 0.8;
/// Pixels the anti-aliased edge spreads over beyond the radius.
const EDGE_PX: f64 = 0.5;
/// Bare metal at a cable's ends: tinned copper or a steel ferrule, silver
/// and glossier than any insulation.
const METAL_BGR: [f64; 3] = [175.0, 178.0, 182.0];
const METAL_GLOSS: f64 = 0.9;

/// Where the shadow of a cable of `radius` under `light` is cast from: the
/// shadow at pixel p is that of the cable at p plus this shift, towards
/// the light. None where the light casts no shadow.
pub(super) fn shadow_shift_px(light: &Light, radius: f64) -> Option<[f64; 2]> {
    let light_xy = light.toward_light[0].hypot(light.toward_light[1]);
    if light.shadow > 0.0 && light_xy > 1e-9 {
        let shift = SHADOW_SHIFT_RADII * radius / light_xy;
        Some([light.toward_light[0] * shift, light.toward_light[1] * shift])
    } else {
        None
    }
}

/// Each pixel's nearest point on the centre line, over a box of the image.
struct Field {
    x0: i32,
    y0: i32,
    width: i32,
    height: i32,
    /// Distance from the centre line.
    distance: Vec<f32>,
    /// The offset from the nearest centre-line point to the pixel.
    offset: Vec<[f32; 2]>,
    /// The arc length of the centre line at that point.
    arc: Vec<f32>,
    /// The centre line's whole length.
    length: f64,
}

impl Field {
    /// The distance at image pixel (x, y), if the field covers it.
    fn distance_at(&self, x: i32, y: i32) -> Option<f32> {
        let (fx, fy) = (x - self.x0, y - self.y0);
        if fx < 0 || fy < 0 || fx >= self.width || fy >= self.height {
            return None;
        }
        Some(self.distance[(fy * self.width + fx) as usize])
    }
}

/// Draws `cable` into `pixels` (CV_32FC3 BGR, row-major) and marks its
/// tube in `mask` (CV_8UC1, 0/255).
pub(super) fn draw(
    pixels: &mut [Vec3f],
    mask: &mut [u8],
    width: i32,
    height: i32,
    cable: &CableSpec,
    light: &Light,
) {
    let radius = cable.diameter_px / 2.0;
    let shadow_shift = shadow_shift_px(light, radius);
    let reach = radius
        + EDGE_PX
        + 1.0
        + shadow_shift.map_or(0.0, |_| {
            (SHADOW_SHIFT_RADII + SHADOW_SOFTNESS_RADII) * radius
        });
    let Some(field) = distance_field(&cable.centerline_px, radius, reach, width, height) else {
        return;
    };

    let l = light.toward_light;
    // Half-way between the light and the viewer, for the highlight.
    let half = super::unit([l[0], l[1], l[2] + 1.0]);
    let insulation = cable.bgr.map(f64::from);
    for fy in 0..field.height {
        let y = field.y0 + fy;
        for fx in 0..field.width {
            let x = field.x0 + fx;
            let i = (fy * field.width + fx) as usize;
            let pixel_index = (y * width + x) as usize;
            let d = f64::from(field.distance[i]);
            if d <= radius {
                mask[pixel_index] = 255;
            }
            let coverage = (radius + EDGE_PX - d).clamp(0.0, 1.0);
            let pixel = &mut pixels[pixel_index];
            if coverage < 1.0
                && let Some([sx, sy]) = shadow_shift
            {
                // The shadow at (x, y) is cast by the part of the cable
                // towards the light from it.
                let caster = field.distance_at(x + sx.round() as i32, y + sy.round() as i32);
                if let Some(caster_d) = caster {
                    let inside = ((radius * (1.0 + SHADOW_SOFTNESS_RADII) - f64::from(caster_d))
                        / (radius * SHADOW_SOFTNESS_RADII))
                        .clamp(0.0, 1.0);
                    let darken = (1.0 - light.shadow * inside) as f32;
                    for c in 0..3 {
                        pixel[c] *= darken;
                    }
                }
            }
            if coverage <= 0.0 {
                continue;
            }
            // The cylinder's normal: across the cable in the image plane,
            // towards the viewer at the middle.
            let [ox, oy] = field.offset[i];
            let (mut nx, mut ny) = (f64::from(ox) / radius, f64::from(oy) / radius);
            let across = nx.hypot(ny);
            if across > 1.0 {
                nx /= across;
                ny /= across;
            }
            let nz = (1.0 - nx * nx - ny * ny).max(0.0).sqrt();
            let diffuse = (nx * l[0] + ny * l[1] + nz * l[2]).max(0.0);
            let arc = f64::from(field.arc[i]);
            let bare = cable.metal_end_px > 0.0
                && (arc < cable.metal_end_px || arc > field.length - cable.metal_end_px);
            let (colour, gloss) = if bare {
                (METAL_BGR, METAL_GLOSS)
            } else {
                (insulation, cable.gloss)
            };
            let specular = gloss
                * 255.0
                * (nx * half[0] + ny * half[1] + nz * half[2])
                    .max(0.0)
                    .powi(SHININESS);
            let coverage = coverage as f32;
            for c in 0..3 {
                let lit = (colour[c] * (AMBIENT + DIFFUSE * diffuse) + specular) as f32;
                pixel[c] = pixel[c] * (1.0 - coverage) + lit * coverage;
            }
        }
    }
}

/// The distance field of the polyline over its bounding box grown by
/// `reach`, cut to the image; `None` when that misses the image. The
/// polyline is first thinned to segments of about half a radius, which
/// moves a smooth curve by a small fraction of a pixel and makes each
/// segment's box worth visiting.
fn distance_field(
    points: &[[f64; 2]],
    radius: f64,
    reach: f64,
    width: i32,
    height: i32,
) -> Option<Field> {
    let step = (radius / 2.0).max(1.0);
    let mut kept: Vec<[f64; 2]> = Vec::new();
    for (i, point) in points.iter().enumerate() {
        let far_enough = kept
            .last()
            .is_none_or(|k| (point[0] - k[0]).hypot(point[1] - k[1]) >= step);
        if far_enough || i + 1 == points.len() {
            kept.push(*point);
        }
    }

    let (mut min_x, mut min_y, mut max_x, mut max_y) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for p in &kept {
        min_x = min_x.min(p[0]);
        min_y = min_y.min(p[1]);
        max_x = max_x.max(p[0]);
        max_y = max_y.max(p[1]);
    }
    let x0 = ((min_x - reach).floor().max(0.0)) as i32;
    let y0 = ((min_y - reach).floor().max(0.0)) as i32;
    let x1 = ((max_x + reach).ceil().min(f64::from(width - 1))) as i32;
    let y1 = ((max_y + reach).ceil().min(f64::from(height - 1))) as i32;
    if x0 > x1 || y0 > y1 {
        return None;
    }
    let (field_width, field_height) = (x1 - x0 + 1, y1 - y0 + 1);
    let size = (field_width * field_height) as usize;
    let mut field = Field {
        x0,
        y0,
        width: field_width,
        height: field_height,
        distance: vec![f32::INFINITY; size],
        offset: vec![[0.0; 2]; size],
        arc: vec![0.0; size],
        length: 0.0,
    };

    for pair in kept.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let length2 = dx * dx + dy * dy;
        let start_arc = field.length;
        field.length += length2.sqrt();
        let sx0 = ((a[0].min(b[0]) - reach).floor() as i32).max(x0);
        let sy0 = ((a[1].min(b[1]) - reach).floor() as i32).max(y0);
        let sx1 = ((a[0].max(b[0]) + reach).ceil() as i32).min(x1);
        let sy1 = ((a[1].max(b[1]) + reach).ceil() as i32).min(y1);
        for y in sy0..=sy1 {
            let py = f64::from(y);
            let row = ((y - y0) * field_width) as usize;
            for x in sx0..=sx1 {
                let px = f64::from(x);
                let t = if length2 > 0.0 {
                    (((px - a[0]) * dx + (py - a[1]) * dy) / length2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let (ox, oy) = (px - (a[0] + t * dx), py - (a[1] + t * dy));
                let d = ox.hypot(oy) as f32;
                let i = row + (x - x0) as usize;
                if d < field.distance[i] {
                    field.distance[i] = d;
                    field.offset[i] = [ox as f32, oy as f32];
                    field.arc[i] = (start_arc + t * length2.sqrt()) as f32;
                }
            }
        }
    }
    Some(field)
}
