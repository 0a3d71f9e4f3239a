//! Numbers for people: a few significant digits, engineering notation with SI prefixes.
//!
//! - [`eng`]`(3.0124606e-9, "s", 3)` is `3.01 ns`, `(13.6037, "s", 3)` is `13.6 s`,
//!   `(50e3, "Pa", 3)` is `50.0 kPa`; micro is written `u` (ASCII, as in `us`, `um`); outside
//!   the prefixes y (1e-24) .. Y (1e24) the value is printed as `1.23e27 Pa`.
//! - [`sig`]`(0.049, 3)` is `4.90e-2`, `(13.6037, 3)` is `13.6`: plain decimals from 0.1 up to
//!   the last significant digit, scientific notation otherwise.
//!
//! Zero prints as `0.00` (with the digits asked for), NaN and infinities as `NaN`, `inf`,
//! `-inf`. Rounding is decimal rounding of the value's exact binary representation (Rust's
//! `{:e}` formatting); the output is never longer than the digits asked for.

use crate::error::{Error, Result};

/// Most significant digits a caller may ask for (an f64 holds 15-17).
pub const MAX_DIGITS: usize = 17;

/// SI prefixes from 1e-24 to 1e24, one per power of 1000.
const PREFIXES: [&str; 17] = [
    "y", "z", "a", "f", "p", "n", "u", "m", "", "k", "M", "G", "T", "P", "E", "Z", "Y",
];

/// Power of ten of the first prefix in [`PREFIXES`].
const FIRST_PREFIX_EXPONENT: i32 = -24;

/// A finite non-zero value rounded to `digits` significant digits: its sign, its digits
/// (`digits` characters, first non-zero) and the power of ten of the first digit.
struct Rounded {
    negative: bool,
    digits: String,
    exponent: i32,
}

impl Rounded {
    fn of(value: f64, digits: usize) -> Rounded {
        let text = format!("{:.*e}", digits - 1, value.abs());
        let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
        Rounded {
            negative: value < 0.0,
            digits: mantissa.replace('.', ""),
            exponent: exponent.parse().unwrap_or(0),
        }
    }

    /// The digits with the decimal point after the first `whole` of them (`whole` >= 1,
    /// padded with zeros), or `whole` <= 0 leading zeros after `0.`.
    fn decimal(&self, whole: i32) -> String {
        let sign = if self.negative { "-" } else { "" };
        if whole <= 0 {
            let zeros = "0".repeat(whole.unsigned_abs() as usize);
            return format!("{sign}0.{zeros}{}", self.digits);
        }
        let whole = whole as usize;
        let padded = format!("{:0<whole$}", self.digits);
        let (int, frac) = padded.split_at(whole);
        if frac.is_empty() {
            format!("{sign}{int}")
        } else {
            format!("{sign}{int}.{frac}")
        }
    }

    /// `d.ddde-2` style.
    fn scientific(&self) -> String {
        format!("{}e{}", self.decimal(1), self.exponent)
    }
}

/// Checks the requested number of significant digits.
fn check_digits(digits: usize) -> Result<()> {
    if (1..=MAX_DIGITS).contains(&digits) {
        Ok(())
    } else {
        Err(Error::invalid(
            "digits",
            digits,
            format!("must be 1..={MAX_DIGITS}"),
        ))
    }
}

/// Zero, NaN and infinities, which have no significant digits: `Some(text)` for them.
fn special(value: f64, digits: usize) -> Option<String> {
    if value.is_nan() || value.is_infinite() {
        Some(value.to_string())
    } else if value == 0.0 {
        Some(
            Rounded {
                negative: false,
                digits: "0".repeat(digits),
                exponent: 0,
            }
            .decimal(1),
        )
    } else {
        None
    }
}

/// `value` with `digits` significant digits: plain decimals for 0.1 <= |value| < 10^digits
/// (after rounding), `4.90e-2` style otherwise. Errors if `digits` is not 1..=17.
pub fn sig(value: f64, digits: usize) -> Result<String> {
    check_digits(digits)?;
    if let Some(text) = special(value, digits) {
        return Ok(text);
    }
    let r = Rounded::of(value, digits);
    Ok(if (-1..digits as i32).contains(&r.exponent) {
        r.decimal(r.exponent + 1)
    } else {
        r.scientific()
    })
}

/// `value` in `unit` with `digits` significant digits and the SI prefix that puts 1 to 3
/// digits before the decimal point: `3.01 ns`, `50.0 kPa`; `1.23e27 Pa` beyond the prefixes
/// y..Y. An empty unit gives the bare number with its prefix (`3.01 n`). Errors if `digits`
/// is not 1..=17.
pub fn eng(value: f64, unit: &str, digits: usize) -> Result<String> {
    check_digits(digits)?;
    let (number, prefix) = match special(value, digits) {
        Some(text) => (text, ""),
        None => {
            let r = Rounded::of(value, digits);
            let power = r.exponent.div_euclid(3) * 3;
            let slot = (power - FIRST_PREFIX_EXPONENT) / 3;
            match usize::try_from(slot).ok().and_then(|k| PREFIXES.get(k)) {
                Some(prefix) => (r.decimal(r.exponent - power + 1), *prefix),
                None => (r.scientific(), ""),
            }
        }
    };
    Ok(if prefix.is_empty() && unit.is_empty() {
        number
    } else {
        format!("{number} {prefix}{unit}")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e3(v: f64, unit: &str) -> String {
        eng(v, unit, 3).unwrap()
    }

    #[test]
    fn engineering_notation_picks_the_prefix_and_keeps_three_digits() {
        assert_eq!(e3(0.0000000030124606451092933, "s"), "3.01 ns");
        assert_eq!(e3(13.603775798000001, "s"), "13.6 s");
        assert_eq!(e3(50e3, "Pa"), "50.0 kPa");
        assert_eq!(e3(123.456e6, "Pa"), "123 MPa");
        assert_eq!(e3(1e-6, "s"), "1.00 us");
        assert_eq!(e3(2e-3, "m"), "2.00 mm");
        assert_eq!(e3(1.0, "Hz"), "1.00 Hz");
        assert_eq!(e3(0.5, "m"), "500 mm");
        assert_eq!(e3(-42.0e-12, "J"), "-42.0 pJ");
        assert_eq!(eng(3.0124606e-9, "s", 4).unwrap(), "3.012 ns");
        assert_eq!(eng(333.3e3, "Hz", 1).unwrap(), "300 kHz");
        assert_eq!(eng(3.0124606e-9, "", 3).unwrap(), "3.01 n");
    }

    #[test]
    fn rounding_that_carries_moves_to_the_next_prefix() {
        assert_eq!(e3(999.6e-9, "s"), "1.00 us");
        assert_eq!(e3(9.9996e-9, "s"), "10.0 ns");
        assert_eq!(e3(99.96, "s"), "100 s");
        assert_eq!(sig(9.996, 3).unwrap(), "10.0");
        assert_eq!(sig(0.09996, 3).unwrap(), "0.100");
    }

    #[test]
    fn zero_nan_infinities_and_values_beyond_the_prefixes_print_as_such() {
        assert_eq!(e3(0.0, "s"), "0.00 s");
        assert_eq!(e3(-0.0, "s"), "0.00 s");
        assert_eq!(e3(f64::NAN, "s"), "NaN s");
        assert_eq!(e3(f64::INFINITY, "Pa"), "inf Pa");
        assert_eq!(e3(f64::NEG_INFINITY, "Pa"), "-inf Pa");
        assert_eq!(e3(1.234e27, "Pa"), "1.23e27 Pa");
        assert_eq!(e3(-5e-30, "m"), "-5.00e-30 m");
        assert_eq!(e3(999.0e24, "Pa"), "999 YPa");
        assert_eq!(e3(f64::MAX, "J"), "1.80e308 J");
        assert_eq!(e3(f64::MIN_POSITIVE * 1e-10, "J"), "2.23e-318 J");
        assert_eq!(sig(0.0, 3).unwrap(), "0.00");
        assert_eq!(sig(0.0, 1).unwrap(), "0");
        assert_eq!(sig(f64::NAN, 3).unwrap(), "NaN");
        assert_eq!(sig(f64::NEG_INFINITY, 3).unwrap(), "-inf");
    }

    #[test]
    fn significant_digits_use_decimals_from_a_tenth_and_exponents_beyond() {
        assert_eq!(sig(0.049, 3).unwrap(), "4.90e-2");
        assert_eq!(sig(3e-16, 2).unwrap(), "3.0e-16");
        assert_eq!(sig(13.603775798, 3).unwrap(), "13.6");
        assert_eq!(sig(0.25, 3).unwrap(), "0.250");
        assert_eq!(sig(-0.9, 2).unwrap(), "-0.90");
        assert_eq!(sig(123.0, 3).unwrap(), "123");
        assert_eq!(sig(1234.0, 3).unwrap(), "1.23e3");
        assert_eq!(sig(1234.0, 4).unwrap(), "1234");
        assert_eq!(sig(1.0, 1).unwrap(), "1");
        assert_eq!(sig(0.1, 1).unwrap(), "0.1");
    }

    #[test]
    fn digits_out_of_range_are_errors_naming_them() {
        for bad in [0, 18, usize::MAX] {
            let e = sig(1.0, bad).unwrap_err().to_string();
            assert!(e.contains(&format!("digits = {bad}")), "{e}");
            assert!(eng(1.0, "s", bad).is_err());
        }
        assert_eq!(sig(1.0 / 3.0, 17).unwrap(), "0.33333333333333331");
    }
}
