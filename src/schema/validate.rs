//! Range checks run while a file is deserialised, so that a bad value is
//! reported at its own line and column (`#[serde(deserialize_with = ...)]`).

use serde::{Deserialize, Deserializer, de::Error};

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

/// A count ≥ 1.
pub fn at_least_one<'de, D: Deserializer<'de>>(d: D) -> Result<usize, D::Error> {
    let v = usize::deserialize(d)?;
    if v >= 1 {
        Ok(v)
    } else {
        Err(D::Error::custom("expected a count ≥ 1, found 0"))
    }
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
    let [low, high] = <[f64; 2]>::deserialize(d)?;
    if (0.0..=3.3).contains(&low) && (low..=3.3).contains(&high) {
        Ok([low, high])
    } else {
        Err(D::Error::custom(format!(
            "expected [low, high] with 0 ≤ low ≤ high ≤ 3.3 V, found [{low}, {high}]"
        )))
    }
}

/// A range `[low, high]` of numbers with 0 ≤ low ≤ high.
pub fn non_negative_range<'de, D: Deserializer<'de>>(d: D) -> Result<[f64; 2], D::Error> {
    let [low, high] = <[f64; 2]>::deserialize(d)?;
    if low >= 0.0 && low <= high && high.is_finite() {
        Ok([low, high])
    } else {
        Err(D::Error::custom(format!(
            "expected [low, high] with 0 ≤ low ≤ high, found [{low}, {high}]"
        )))
    }
}
