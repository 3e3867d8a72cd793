//! The tactile map drawn on a character canvas, with the fitted line and
//! the centroids over it.

use cablecell::geometry::LineInSensor;
use cablecell::perception::tactile::{TAXEL_COLS, TAXEL_ROWS, TactileMap};

/// Canvas cells per taxel: terminal cells are about twice as tall as wide.
const CELL_COLS: usize = 8;
const CELL_ROWS: usize = 4;
const SHADES: [char; 5] = [' ', '░', '▒', '▓', '█'];

/// The map drawn on a character canvas in the sensor frame (x right, y up),
/// with the line and the centroids over it.
pub(super) fn draw_map(
    map: &TactileMap,
    pitch_mm: f64,
    line: Option<LineInSensor>,
    centroids: &[(f64, f64)],
) -> Vec<String> {
    let (width, height) = (TAXEL_COLS * CELL_COLS, TAXEL_ROWS * CELL_ROWS);
    let peak = map.peak_dv_v().max(1e-9);
    let x_mm = |cx: usize| ((cx as f64 + 0.5) / CELL_COLS as f64 - 2.5) * pitch_mm;
    let y_mm = |cy: usize| (2.5 - (cy as f64 + 0.5) / CELL_ROWS as f64) * pitch_mm;
    let mut canvas: Vec<Vec<char>> = (0..height)
        .map(|cy| {
            (0..width)
                .map(|cx| {
                    let dv = map.dv_v[cy / CELL_ROWS][cx / CELL_COLS].max(0.0);
                    let level = ((dv / peak) * (SHADES.len() - 1) as f64).round() as usize;
                    SHADES[level.min(SHADES.len() - 1)]
                })
                .collect()
        })
        .collect();
    if let Some(line) = line {
        let (sin, cos) = line.alpha_rad.sin_cos();
        // A canvas cell is marked if the line crosses it: its centre lies
        // within the cell's half extent along the line's normal.
        let (cell_w_mm, cell_h_mm) = (pitch_mm / CELL_COLS as f64, pitch_mm / CELL_ROWS as f64);
        let half_extent_mm = 0.5 * (sin.abs() * cell_w_mm + cos.abs() * cell_h_mm);
        for (cy, row) in canvas.iter_mut().enumerate() {
            for (cx, cell) in row.iter_mut().enumerate() {
                let distance_mm = -sin * x_mm(cx) + cos * y_mm(cy) - line.n_mm;
                if distance_mm.abs() <= half_extent_mm {
                    *cell = '*';
                }
            }
        }
    }
    for &(x, y) in centroids {
        let cx = ((x / pitch_mm + 2.5) * CELL_COLS as f64).floor();
        let cy = ((2.5 - y / pitch_mm) * CELL_ROWS as f64).floor();
        if (0.0..width as f64).contains(&cx) && (0.0..height as f64).contains(&cy) {
            canvas[cy as usize][cx as usize] = 'o';
        }
    }
    canvas
        .into_iter()
        .map(|row| row.into_iter().collect())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_horizontal_line_near_the_middle_marks_the_row_it_crosses() {
        let map = TactileMap::from_fn(|row, _| if row == 2 { 0.5 } else { 0.0 });
        let line = LineInSensor::new(0.0, 0.1);
        let rows = draw_map(&map, 3.55, Some(line), &[(0.0, 0.0)]);
        assert_eq!(rows.len(), TAXEL_ROWS * CELL_ROWS);
        let marked: Vec<usize> = rows
            .iter()
            .enumerate()
            .filter(|(_, r)| r.contains('*'))
            .map(|(i, _)| i)
            .collect();
        assert_eq!(marked, [9]);
        assert_eq!(
            rows[9].chars().filter(|c| *c == '*').count(),
            TAXEL_COLS * CELL_COLS
        );
        assert_eq!(rows[10].chars().nth(20), Some('o'));
        assert!(rows[0].chars().all(|c| c == ' '));
        assert!(rows[8].contains('█'));
    }
}
