//! The tactile map: one Δv per taxel, laid out as the paper's 5×5 grid.
//!
//! Row `i` and column `j` are 0-based here; the paper's taxel c_ij is
//! `[i - 1][j - 1]`. Row 0 is the top row (y = +2·pitch), column 0 the left
//! column (x = -2·pitch); row-major order is c11, c12, …, c15, c21, …, c55.

use schemars::JsonSchema;
use serde::Serialize;

pub const TAXEL_ROWS: usize = 5;
pub const TAXEL_COLS: usize = 5;
pub const TAXEL_COUNT: usize = TAXEL_ROWS * TAXEL_COLS;

/// Full-scale of the MCU's 12-bit ADC.
pub const ADC_MAX: u16 = 4095;

/// Volts per ADC count: the 3.3 V reference over 4096 counts. Scaling by a
/// power of two is exact, so `raw * VOLTS_PER_COUNT == raw * 3.3 / 4096`.
pub(super) const VOLTS_PER_COUNT: f64 = 3.3 / 4096.0;

/// Volts of a 12-bit ADC count.
///
/// The MCU sends each count in two bytes; only the low nibble of the high
/// byte is data, so anything above bit 11 is masked off rather than
/// trusted.
pub fn raw_to_volts(raw: u16) -> f64 {
    f64::from(raw & ADC_MAX) * VOLTS_PER_COUNT
}

/// Half the pad's side, in pitches: the outer taxels sit 2 pitches from
/// the centre and the silicone cap goes on half a pitch beyond them.
pub const PAD_HALF_SIDE_PITCH: f64 = 2.5;

/// x of column `col` (0-based) in the sensor frame, in mm.
pub fn taxel_x_mm(col: usize, pitch_mm: f64) -> f64 {
    (col as f64 - 2.0) * pitch_mm
}

/// y of row `row` (0-based, row 0 at the top) in the sensor frame, in mm.
pub fn taxel_y_mm(row: usize, pitch_mm: f64) -> f64 {
    (2.0 - row as f64) * pitch_mm
}

/// Voltage variation of every taxel after bias removal, `[row][col]`.
///
/// Positive Δv means the silicone is pressed there. A taxel flagged in
/// `saturated` read the ADC's full scale, so its Δv is only a lower bound.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, JsonSchema)]
pub struct TactileMap {
    pub dv_v: [[f64; TAXEL_COLS]; TAXEL_ROWS],
    pub saturated: [[bool; TAXEL_COLS]; TAXEL_ROWS],
}

impl TactileMap {
    /// A map from 25 finite values in row-major order (c11..c55), nothing
    /// saturated.
    pub fn from_row_major(values: &[f64]) -> Result<Self, MapError> {
        if values.len() != TAXEL_COUNT {
            return Err(MapError::WrongCount {
                found: values.len(),
            });
        }
        if let Some((index, &value)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(MapError::NotFinite { index, value });
        }
        Ok(Self::from_fn(|row, col| values[row * TAXEL_COLS + col]))
    }

    /// A map with `dv_v[row][col] = f(row, col)`, nothing saturated.
    ///
    /// Unlike the other constructors this does not check the values: it is
    /// for renderers that produce them by construction.
    pub fn from_fn(mut f: impl FnMut(usize, usize) -> f64) -> Self {
        let mut dv_v = [[0.0; TAXEL_COLS]; TAXEL_ROWS];
        for (row, values) in dv_v.iter_mut().enumerate() {
            for (col, value) in values.iter_mut().enumerate() {
                *value = f(row, col);
            }
        }
        Self {
            dv_v,
            saturated: [[false; TAXEL_COLS]; TAXEL_ROWS],
        }
    }

    /// A map from text: a JSON array of 25 numbers, flat or as 5 rows of
    /// 5, or 25 numbers separated by whitespace and/or commas.
    ///
    /// Errors name the offending token by its value index and its line and
    /// column in `text`, so a hand-edited fixture can be fixed at once.
    pub fn parse(text: &str) -> Result<Self, MapError> {
        let (tokens, end) = tokenize(text);
        let values = match tokens.first() {
            Some(Token {
                kind: TokenKind::Open,
                ..
            }) => JsonParser::new(&tokens, end).parse()?,
            _ => parse_separated(&tokens)?,
        };
        if values.count != TAXEL_COUNT {
            return Err(MapError::WrongCount {
                found: values.count,
            });
        }
        Self::from_row_major(&values.values)
    }

    /// The largest Δv, in volts (NaN entries are ignored).
    pub fn peak_dv_v(&self) -> f64 {
        self.dv_v
            .iter()
            .flatten()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max)
    }
}

/// A tactile map could not be built from the given values or text.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MapError {
    /// Not exactly one value per taxel: a reading was lost or duplicated,
    /// or the data is not from a 5×5 pad.
    #[error("a tactile map needs {} values, found {found}", TAXEL_COUNT)]
    WrongCount { found: usize },
    /// A value handed in as a number is NaN or infinite; fix the code or
    /// file that produced it.
    #[error("value {index} (counting from 0) is {value}, not a finite voltage")]
    NotFinite { index: usize, value: f64 },
    /// A token in the text is not a finite number.
    #[error(
        "line {line}, column {column}: `{token}` (value {index}, counting from 0) is not a finite number"
    )]
    BadToken {
        index: usize,
        token: String,
        line: usize,
        column: usize,
    },
    /// The JSON structure is broken: a bracket or comma is missing or out
    /// of place.
    #[error("line {line}, column {column}: expected {expected}, found {found}")]
    Syntax {
        expected: &'static str,
        found: String,
        line: usize,
        column: usize,
    },
    /// A row of a nested JSON map does not hold 5 values.
    #[error(
        "line {line}, column {column}: row {row} (counting from 0) has {found} values, a row needs {}",
        TAXEL_COLS
    )]
    BadRow {
        row: usize,
        found: usize,
        line: usize,
        column: usize,
    },
}

/// Values read so far: the first 25 kept, all of them counted so that a
/// wrong count can be reported in full.
struct Values {
    values: [f64; TAXEL_COUNT],
    count: usize,
}

impl Values {
    fn new() -> Self {
        Self {
            values: [0.0; TAXEL_COUNT],
            count: 0,
        }
    }

    fn push(&mut self, word: &str, at: Position) -> Result<(), MapError> {
        let value = word
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| MapError::BadToken {
                index: self.count,
                token: word.to_owned(),
                line: at.line,
                column: at.column,
            })?;
        if let Some(slot) = self.values.get_mut(self.count) {
            *slot = value;
        }
        self.count += 1;
        Ok(())
    }
}

/// 1-based line and column (in characters) in the text.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Position {
    line: usize,
    column: usize,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum TokenKind<'a> {
    Open,
    Close,
    Comma,
    Word(&'a str),
}

#[derive(Clone, Copy, Debug)]
struct Token<'a> {
    kind: TokenKind<'a>,
    at: Position,
}

impl Token<'_> {
    fn syntax_error(&self, expected: &'static str) -> MapError {
        let found = match self.kind {
            TokenKind::Open => "`[`".to_owned(),
            TokenKind::Close => "`]`".to_owned(),
            TokenKind::Comma => "`,`".to_owned(),
            TokenKind::Word(word) => format!("`{word}`"),
        };
        MapError::Syntax {
            expected,
            found,
            line: self.at.line,
            column: self.at.column,
        }
    }
}

fn is_delimiter(c: char) -> bool {
    c.is_whitespace() || matches!(c, '[' | ']' | ',')
}

/// Brackets, commas and words (runs of anything else), and the position
/// just past the end of the text.
fn tokenize(text: &str) -> (Vec<Token<'_>>, Position) {
    let mut tokens = Vec::new();
    let mut at = Position { line: 1, column: 1 };
    let mut word_start: Option<(usize, Position)> = None;
    for (offset, c) in text.char_indices() {
        if is_delimiter(c) {
            if let Some((start, start_at)) = word_start.take() {
                tokens.push(Token {
                    kind: TokenKind::Word(&text[start..offset]),
                    at: start_at,
                });
            }
            let kind = match c {
                '[' => Some(TokenKind::Open),
                ']' => Some(TokenKind::Close),
                ',' => Some(TokenKind::Comma),
                _ => None,
            };
            if let Some(kind) = kind {
                tokens.push(Token { kind, at });
            }
        } else if word_start.is_none() {
            word_start = Some((offset, at));
        }
        if c == '\n' {
            at.line += 1;
            at.column = 1;
        } else {
            at.column += 1;
        }
    }
    if let Some((start, start_at)) = word_start {
        tokens.push(Token {
            kind: TokenKind::Word(&text[start..]),
            at: start_at,
        });
    }
    (tokens, at)
}

/// Numbers separated by whitespace and/or commas; brackets are an error.
fn parse_separated(tokens: &[Token<'_>]) -> Result<Values, MapError> {
    let mut values = Values::new();
    for token in tokens {
        match token.kind {
            TokenKind::Comma => {}
            TokenKind::Word(word) => values.push(word, token.at)?,
            TokenKind::Open | TokenKind::Close => return Err(token.syntax_error("a number")),
        }
    }
    Ok(values)
}

/// Strict JSON for the two shapes a map may take: `[v, ...]` or
/// `[[v, ...], ...]`.
struct JsonParser<'t, 'a> {
    tokens: &'t [Token<'a>],
    next: usize,
    end: Position,
}

impl<'t, 'a> JsonParser<'t, 'a> {
    fn new(tokens: &'t [Token<'a>], end: Position) -> Self {
        Self {
            tokens,
            next: 0,
            end,
        }
    }

    fn take(&mut self, expected: &'static str) -> Result<Token<'a>, MapError> {
        let token = self
            .tokens
            .get(self.next)
            .copied()
            .ok_or(MapError::Syntax {
                expected,
                found: "end of text".to_owned(),
                line: self.end.line,
                column: self.end.column,
            })?;
        self.next += 1;
        Ok(token)
    }

    /// After an element: `,` means another follows, `]` closes the array.
    fn more_elements(&mut self) -> Result<bool, MapError> {
        let token = self.take("`,` or `]`")?;
        match token.kind {
            TokenKind::Comma => Ok(true),
            TokenKind::Close => Ok(false),
            _ => Err(token.syntax_error("`,` or `]`")),
        }
    }

    fn parse(mut self) -> Result<Values, MapError> {
        let mut values = Values::new();
        self.take("`[`")?;
        // Whether the elements are rows; decided by the first element.
        let mut nested = None;
        let mut rows = 0;
        let mut first = true;
        loop {
            let token = self.take("a number, `[` or `]`")?;
            match (token.kind, nested) {
                (TokenKind::Close, _) if first => break,
                (TokenKind::Word(word), None | Some(false)) => {
                    nested = Some(false);
                    values.push(word, token.at)?;
                }
                (TokenKind::Open, None | Some(true)) => {
                    nested = Some(true);
                    let before = values.count;
                    self.parse_row(&mut values)?;
                    let found = values.count - before;
                    if found != TAXEL_COLS {
                        return Err(MapError::BadRow {
                            row: rows,
                            found,
                            line: token.at.line,
                            column: token.at.column,
                        });
                    }
                    rows += 1;
                }
                (_, Some(true)) => return Err(token.syntax_error("`[` opening a row")),
                (_, Some(false)) => return Err(token.syntax_error("a number")),
                (_, None) => return Err(token.syntax_error("a number or `[`")),
            }
            first = false;
            if !self.more_elements()? {
                break;
            }
        }
        if let Some(extra) = self.tokens.get(self.next) {
            return Err(extra.syntax_error("end of text"));
        }
        Ok(values)
    }

    /// The numbers of one row, after its `[`, up to and including its `]`.
    fn parse_row(&mut self, values: &mut Values) -> Result<(), MapError> {
        let mut first = true;
        loop {
            let token = self.take("a number or `]`")?;
            match token.kind {
                TokenKind::Close if first => return Ok(()),
                TokenKind::Word(word) => values.push(word, token.at)?,
                _ => return Err(token.syntax_error("a number")),
            }
            first = false;
            if !self.more_elements()? {
                return Ok(());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp() -> Vec<f64> {
        (0..TAXEL_COUNT).map(|k| k as f64 * 0.1 - 1.0).collect()
    }

    fn assert_ramp(map: &TactileMap) {
        let expected = TactileMap::from_row_major(&ramp()).unwrap();
        assert_eq!(map, &expected);
        // Row-major: c12 is the second value, c21 the sixth.
        assert_eq!(map.dv_v[0][1], -0.9);
        assert_eq!(map.dv_v[1][0], ramp()[5]);
    }

    #[test]
    fn raw_to_volts_scales_and_masks_the_high_nibble() {
        assert_eq!(raw_to_volts(0), 0.0);
        assert_eq!(raw_to_volts(2048), 1.65);
        assert_eq!(raw_to_volts(ADC_MAX), 4095.0 * 3.3 / 4096.0);
        assert_eq!(raw_to_volts(0xF000 | 0x0123), raw_to_volts(0x0123));
        assert_eq!(raw_to_volts(0x1000), 0.0);
    }

    #[test]
    fn taxel_coordinates_follow_the_paper() {
        // c11 at top left, c35 on the +x side, c13 on the +y side.
        assert_eq!((taxel_x_mm(0, 3.55), taxel_y_mm(0, 3.55)), (-7.1, 7.1));
        assert_eq!((taxel_x_mm(4, 3.55), taxel_y_mm(2, 3.55)), (7.1, 0.0));
        assert_eq!((taxel_x_mm(2, 3.55), taxel_y_mm(0, 3.55)), (0.0, 7.1));
    }

    #[test]
    fn from_row_major_checks_count_and_finiteness() {
        assert_ramp(&TactileMap::from_row_major(&ramp()).unwrap());
        assert_eq!(
            TactileMap::from_row_major(&ramp()[..24]),
            Err(MapError::WrongCount { found: 24 })
        );
        let mut values = ramp();
        values[7] = f64::NAN;
        assert!(matches!(
            TactileMap::from_row_major(&values),
            Err(MapError::NotFinite { index: 7, .. })
        ));
    }

    fn text(values: &[f64], separator: &str, per_line: usize) -> String {
        values
            .chunks(per_line)
            .map(|line| {
                line.iter()
                    .map(f64::to_string)
                    .collect::<Vec<_>>()
                    .join(separator)
            })
            .collect::<Vec<_>>()
            .join("\n")
    }

    #[test]
    fn parses_flat_and_nested_json() {
        let flat = serde_json::to_string(&ramp()).unwrap();
        assert_ramp(&TactileMap::parse(&flat).unwrap());
        let rows: Vec<Vec<f64>> = ramp().chunks(TAXEL_COLS).map(<[f64]>::to_vec).collect();
        let nested = serde_json::to_string_pretty(&rows).unwrap();
        assert_ramp(&TactileMap::parse(&nested).unwrap());
    }

    #[test]
    fn parses_whitespace_and_comma_separated() {
        assert_ramp(&TactileMap::parse(&text(&ramp(), " ", 5)).unwrap());
        assert_ramp(&TactileMap::parse(&text(&ramp(), "\t", 25)).unwrap());
        assert_ramp(&TactileMap::parse(&text(&ramp(), ", ", 5)).unwrap());
        assert_ramp(&TactileMap::parse(&format!("  {}\n", text(&ramp(), ",", 7))).unwrap());
    }

    #[test]
    fn wrong_count_says_how_many() {
        let short = text(&ramp()[..24], " ", 5);
        assert_eq!(
            TactileMap::parse(&short),
            Err(MapError::WrongCount { found: 24 })
        );
        let mut long = ramp();
        long.push(0.0);
        let long_json = serde_json::to_string(&long).unwrap();
        let err = TactileMap::parse(&long_json).unwrap_err();
        assert_eq!(err, MapError::WrongCount { found: 26 });
        assert_eq!(err.to_string(), "a tactile map needs 25 values, found 26");
        assert_eq!(
            TactileMap::parse(""),
            Err(MapError::WrongCount { found: 0 })
        );
        assert_eq!(
            TactileMap::parse("[]"),
            Err(MapError::WrongCount { found: 0 })
        );
    }

    #[test]
    fn bad_token_is_named_with_its_place() {
        let err = TactileMap::parse("0 0 0 0 0\n0 0 x 0 0\n").unwrap_err();
        assert_eq!(
            err,
            MapError::BadToken {
                index: 7,
                token: "x".into(),
                line: 2,
                column: 5
            }
        );
        assert!(
            err.to_string()
                .starts_with("line 2, column 5: `x` (value 7")
        );
        // Non-finite spellings that Rust would parse are refused too.
        let err = TactileMap::parse("[1, 2,\n  inf]").unwrap_err();
        assert!(matches!(
            err,
            MapError::BadToken {
                index: 2,
                line: 2,
                column: 3,
                ..
            }
        ));
        // Columns count characters, not bytes.
        let err = TactileMap::parse("Δ 1").unwrap_err();
        assert!(matches!(
            err,
            MapError::BadToken {
                index: 0,
                line: 1,
                column: 1,
                ..
            }
        ));
        let err = TactileMap::parse("1 Δv").unwrap_err();
        assert!(matches!(
            err,
            MapError::BadToken {
                index: 1,
                column: 3,
                ..
            }
        ));
    }

    #[test]
    fn broken_json_is_a_syntax_error_with_its_place() {
        let syntax = |text: &str| match TactileMap::parse(text) {
            Err(MapError::Syntax {
                expected,
                line,
                column,
                ..
            }) => (expected, line, column),
            other => panic!("{text}: {other:?}"),
        };
        assert_eq!(syntax("[1, 2 3]"), ("`,` or `]`", 1, 7));
        assert_eq!(syntax("[1, 2,\n"), ("a number, `[` or `]`", 2, 1));
        assert_eq!(syntax("[1, [2]]"), ("a number", 1, 5));
        assert_eq!(syntax("[[1,2,3,4,5], 2]"), ("`[` opening a row", 1, 15));
        assert_eq!(syntax("[,1]"), ("a number or `[`", 1, 2));
        assert_eq!(syntax("[[[1]]]"), ("a number", 1, 3));
        assert_eq!(syntax("[1] 2"), ("end of text", 1, 5));
        assert_eq!(syntax("1 2 ]"), ("a number", 1, 5));
    }

    #[test]
    fn nested_rows_must_hold_five() {
        let rows = "[[1,2,3,4,5],[1,2,3,4,5],\n [1,2,3,4],[1,2,3,4,5,6],[1,2,3,4,5]]";
        assert_eq!(
            TactileMap::parse(rows),
            Err(MapError::BadRow {
                row: 2,
                found: 4,
                line: 2,
                column: 2
            })
        );
    }

    #[test]
    fn peak_ignores_nan() {
        let mut map = TactileMap::from_row_major(&ramp()).unwrap();
        assert_eq!(map.peak_dv_v(), ramp()[24]);
        map.dv_v[4][4] = f64::NAN;
        assert_eq!(map.peak_dv_v(), ramp()[23]);
    }
}
