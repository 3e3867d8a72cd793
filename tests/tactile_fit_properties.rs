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
    let mut worst_alpha = (0.0_f64, 0.0, 0.0, 0.0);
    let mut worst_offset = (0.0_f64, 0.0, 0.0, 0.0);
    let mut errs = 0;
    let n_a = 720;
    let n_o = 60;
    for amp in [0.2, 0.5, 1.5] {
        for ia in 0..=n_a {
            let alpha = -FRAC_PI_2 + PI * ia as f64 / n_a as f64;
            for io in 0..=n_o {
                let offset = -1.5 * PITCH + 3.0 * PITCH * io as f64 / n_o as f64;
                let truth = LineInSensor::new(alpha, offset);
                match fit_wire(&render_line(truth, amp), &config) {
                    Ok(fit) => {
                        let (da, dn) = line_error(&fit.line, &truth);
                        if da.abs() > worst_alpha.0 {
                            worst_alpha = (da.abs(), alpha, offset, amp);
                        }
                        if dn.abs() > worst_offset.0 {
                            worst_offset = (dn.abs(), alpha, offset, amp);
                        }
                    }
                    Err(e) => {
                        errs += 1;
                        if errs < 10 {
                            println!("err {alpha} {offset} {amp}: {e}");
                        }
                    }
                }
            }
        }
    }
    println!("errors {errs}");
    println!("worst alpha {worst_alpha:?}");
    println!("worst offset {worst_offset:?}");
}
