//! Range checks run while a file is deserialised, so that a bad value is
//! reported at its own line and column (`#[serde(deserialize_with = ...)]`).

use std::ops::RangeInclusive;

use serde::{Deserialize, Deserializer, de::Error};

/// A value in `range` (`unit` names its unit in the message, if it has
/// one). A field with a range of its own uses it through a function beside
/// the field whose doc comment says why that range.
pub fn within<'de, D, T>(d: D, range: RangeInclusive<T>, unit: &str) -> Result<T, D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de> + Bound,
{
    check_within(T::deserialize(d)?, &range, unit).map_err(D::Error::custom)
}

/// [`within`] for a value that comes from elsewhere than a file (a command
/// line option): the value, or the message that refuses it. A NaN is in no
/// range.
pub fn check_within<T: Bound>(
    value: T,
    range: &RangeInclusive<T>,
    unit: &str,
) -> Result<T, String> {
    if range.contains(&value) {
        return Ok(value);
    }
    Err(format!(
        "expected a value in [{}, {}]{}, found {}",
        range.start().text(),
        range.end().text(),
        spaced(unit),
        value.text()
    ))
}

/// ` unit`, or nothing for a number without one.
fn spaced(unit: &str) -> String {
    if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    }
}

/// A number a range can bound, written short in messages.
pub trait Bound: PartialOrd + Copy {
    fn text(self) -> String;
}

impl Bound for f64 {
    /// Very large and very small numbers in exponent form (`1e308`, not
    /// 309 digits).
    fn text(self) -> String {
        let magnitude = self.abs();
        if magnitude != 0.0 && !(1e-4..1e9).contains(&magnitude) {
            format!("{self:e}")
        } else {
            format!("{self}")
        }
    }
}

macro_rules! integer_bound {
    ($($t:ty),*) => {$(
        impl Bound for $t {
            fn text(self) -> String {
                self.to_string()
            }
        }
    )*};
}
integer_bound!(u8, u32, u64, usize, i32);

/// A number > 0.
pub fn positive<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    let v = f64::deserialize(d)?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(D::Error::custom(format!(
            "expected a number > 0, found {v}"
        )))
    }
}

/// A number ≥ 0.
pub fn non_negative<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    let v = f64::deserialize(d)?;
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(D::Error::custom(format!(
            "expected a number ≥ 0, found {v}"
        )))
    }
}

/// A finite number.
pub fn finite<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    let v = f64::deserialize(d)?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(D::Error::custom(format!(
            "expected a finite number, found {v}"
        )))
    }
}

/// An angle in (-π/2, π/2]: a cable's direction on the pad.
pub fn line_angle<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    let v = f64::deserialize(d)?;
    if v > -std::f64::consts::FRAC_PI_2 && v <= std::f64::consts::FRAC_PI_2 {
        Ok(v)
    } else {
        Err(D::Error::custom(format!(
            "expected an angle in (-π/2, π/2] rad, found {v}"
        )))
    }
}

/// An angle in [0, π/2]: the spread of a line's direction, which is only
/// known modulo π.
pub fn angle_spread<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    let v = f64::deserialize(d)?;
    if (0.0..=std::f64::consts::FRAC_PI_2).contains(&v) {
        Ok(v)
    } else {
        Err(D::Error::custom(format!(
            "expected an angle in [0, π/2] rad, found {v}"
        )))
    }
}

/// A fraction in [0, 1].
pub fn fraction<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    let v = f64::deserialize(d)?;
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(D::Error::custom(format!(
            "expected a fraction in [0, 1], found {v}"
        )))
    }
}

/// A fraction in [0, 1], for an optional key (`#[serde(default)]` makes
/// it `None` when absent).
pub fn some_fraction<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    fraction(d).map(Some)
}

/// A count of moves the cell makes one after the other, in 1..=100:
/// more would keep a cell busy for many minutes, a likely slip.
pub fn moves<'de, D: Deserializer<'de>>(d: D) -> Result<usize, D::Error> {
    let v = usize::deserialize(d)?;
    if (1..=100).contains(&v) {
        Ok(v)
    } else {
        Err(D::Error::custom(format!(
            "expected a count in 1..=100, found {v}"
        )))
    }
}

/// Three finite numbers.
pub fn vector3<'de, D: Deserializer<'de>>(d: D) -> Result<[f64; 3], D::Error> {
    let v = <[f64; 3]>::deserialize(d)?;
    if v.iter().all(|x| x.is_finite()) {
        Ok(v)
    } else {
        Err(D::Error::custom("expected three finite numbers"))
    }
}

/// Three finite numbers, not all zero: a direction (normalised by its user).
pub fn unit_vector3<'de, D: Deserializer<'de>>(d: D) -> Result<[f64; 3], D::Error> {
    let v = vector3(d)?;
    if v.iter().map(|x| x * x).sum::<f64>() > 1e-12 {
        Ok(v)
    } else {
        Err(D::Error::custom(
            "expected a direction, found a zero vector",
        ))
    }
}

/// A range of voltages `[low, high]` within the 3.3 V ADC.
pub fn voltage_range<'de, D: Deserializer<'de>>(d: D) -> Result<[f64; 2], D::Error> {
    range_within(d, 0.0..=3.3, "V")
}

/// A range `[low, high]` of numbers, low ≤ high, both in `bounds`.
pub fn range_within<'de, D: Deserializer<'de>>(
    d: D,
    bounds: RangeInclusive<f64>,
    unit: &str,
) -> Result<[f64; 2], D::Error> {
    let [low, high] = <[f64; 2]>::deserialize(d)?;
    if bounds.contains(&low) && bounds.contains(&high) && low <= high {
        Ok([low, high])
    } else {
        Err(D::Error::custom(format!(
            "expected [low, high] with {} ≤ low ≤ high ≤ {}{}, found [{}, {}]",
            bounds.start().text(),
            bounds.end().text(),
            spaced(unit),
            low.text(),
            high.text()
        )))
    }
}
