//! Property tests of the tactile fit on synthetic cables.

use std::f64::consts::{FRAC_PI_2, PI};

use cablecell::geometry::LineInSensor;
use cablecell::perception::tactile::map::{taxel_x_mm, taxel_y_mm};
use cablecell::perception::tactile::{FitConfig, PAPER_PITCH_MM, TactileMap, fit_wire};
use nalgebra::Vector2;

const PITCH: f64 = PAPER_PITCH_MM;
const SIGMA_MM: f64 = 0.55 * PITCH;

fn render_line(line: LineInSensor, amplitude_v: f64) -> TactileMap {
    TactileMap::from_fn(|row, col| {
        let p = Vector2::new(taxel_x_mm(col, PITCH), taxel_y_mm(row, PITCH));
        let d = line.distance_mm(p);
        amplitude_v * (-d * d / (2.0 * SIGMA_MM * SIGMA_MM)).exp()
    })
}

/// Angle and offset error of `fit` against `truth`, the offset compared
/// along the same normal (the two normals flip across alpha = ±π/2).
fn line_error(fit: &LineInSensor, truth: &LineInSensor) -> (f64, f64) {
    let d_alpha = LineInSensor::new(fit.alpha_rad - truth.alpha_rad, 0.0).alpha_rad;
    let same_side = fit.normal().dot(&truth.normal()) >= 0.0;
    let truth_offset = if same_side { truth.offset_mm } else { -truth.offset_mm };
    (d_alpha, fit.offset_mm - truth_offset)
}

#[test]
#[ignore = "a scan that prints the worst cases; run with --ignored --nocapture"]
fn scan_worst_case() {
    let config = FitConfig::default();
    let offs = [0.25, 0.5, 1.0, 1.5];
    let angs = [5.0, 10.0, 20.0, 30.0, 40.0, 45.0];
    let mut table = [[(0.0_f64, 0.0_f64); 6]; 4];
    let mut worst = [[(0.0, 0.0, 0.0, 0.0); 6]; 4];
    let n_a = 1440;
    let n_o = 120;
    for amp in [0.2, 0.35, 0.5, 1.0, 1.5] {
        for ia in 0..=n_a {
            let alpha = -FRAC_PI_2 + PI * ia as f64 / n_a as f64;
            let from_axis = (alpha.abs().min(FRAC_PI_2 - alpha.abs())).to_degrees();
            for io in 0..=n_o {
                let offset = -1.5 * PITCH + 3.0 * PITCH * io as f64 / n_o as f64;
                let truth = LineInSensor::new(alpha, offset);
                let fit = fit_wire(&render_line(truth, amp), &config).unwrap();
                let (da, dn) = line_error(&fit.line, &truth);
                let oi = offs.iter().position(|&o| offset.abs() <= o * PITCH + 1e-9).unwrap();
                let ai = angs.iter().position(|&a| from_axis <= a + 1e-9).unwrap();
                for o in oi..4 { for a in ai..6 {
                    let e = &mut table[o][a];
                    if da.abs() > e.0 { e.0 = da.abs(); worst[o][a].0 = alpha; worst[o][a].1 = offset; }
                    if dn.abs() > e.1 { e.1 = dn.abs(); worst[o][a].2 = alpha; worst[o][a].3 = offset; }
                }}
            }
        }
    }
    println!("rows: |offset| <= k pitch; cols: angle from nearest axis <= deg; cells: max |d alpha| mrad / max |d offset| mm");
    for (o, row) in table.iter().enumerate() {
        let cells: Vec<String> = row.iter().map(|(a, n)| format!("{:7.1}/{:5.3}", a * 1e3, n)).collect();
        println!("{:4} {}", offs[o], cells.join(" "));
    }
    println!("{worst:?}");
}

#[test]
#[ignore]
fn probe() {
    let config = FitConfig::default();
    for deg in [0.5, 1.0, 2.0, 3.0, 5.0, 10.0, 20.0, 30.0, 40.0, 45.0] {
        let truth = LineInSensor::new(f64::to_radians(deg), 0.0);
        let fit = fit_wire(&render_line(truth, 1.0), &config).unwrap();
        let (da, dn) = line_error(&fit.line, &truth);
        let ys: Vec<String> = fit.centroids.iter().map(|c| format!("({:.3},{:.4})", c.x_mm, c.y_mm - (c.x_mm * truth.alpha_rad.tan()))).collect();
        println!("{deg}: {:?} da {:.2} mrad dn {:.4} {}", fit.direction, da * 1e3, dn, ys.join(" "));
    }
}

#[test]
#[ignore]
fn probe_fine() {
    let config = FitConfig::default();
    let mut wa = (0.0_f64, 0.0, 0.0, 0.0);
    let mut wn = (0.0_f64, 0.0, 0.0, 0.0);
    for ai in 0..=20 { let amp = 0.2 + 1.3 * ai as f64 / 20.0;
    for side in [-1.0, 1.0] {
        for k in 0..=4000 {
            let alpha = side * (0.5 + 0.4 * k as f64 / 4000.0);
            for io in 0..=40 {
                let o = 1.5 * PITCH * (0.8 + 0.2 * io as f64 / 40.0);
                for offset in [o, -o] {
                    let truth = LineInSensor::new(alpha, offset);
                    let fit = fit_wire(&render_line(truth, amp), &config).unwrap();
                    let (da, dn) = line_error(&fit.line, &truth);
                    if da.abs() > wa.0 { wa = (da.abs(), alpha, offset, amp); }
                    if dn.abs() > wn.0 { wn = (dn.abs(), alpha, offset, amp); }
                }
            }
        }
    }}
    println!("alpha {wa:?}\noffset {wn:?}");
}
