//! The text of numbers in every output file, the same for both bodies: times and coordinates
//! rounded to [`TIME_DIGITS`] significant digits (`t = 3.0300000000000002` reads `3.03`; the
//! exact value stays `step · Δt`), written as Rust's `Display` writes the rounded value; every
//! other value in the shortest text that reads back to the same double, with an exponent when
//! that is shorter (Żmij: `1.5e-7`, `0.25`, `3.0`).

use std::io::Write;

/// Significant digits of the times and coordinates in the outputs.
pub const TIME_DIGITS: usize = 12;

/// `t` rounded to [`TIME_DIGITS`] significant digits: the double its 12-digit decimal text
/// reads back to (0 and non-finite values unchanged).
pub fn output_time(t: f64) -> f64 {
    if t == 0.0 || !t.is_finite() {
        return t;
    }
    // `-d.ddddddddddde-308`: at most 19 bytes.
    let mut text = [0u8; 32];
    let mut at = &mut text[..];
    write!(at, "{:.*e}", TIME_DIGITS - 1, t).expect("the text fits");
    let len = 32 - at.len();
    std::str::from_utf8(&text[..len])
        .expect("ASCII")
        .parse()
        .expect("a formatted float parses")
}

/// Appends the text of a time or coordinate: `output_time(t)` as `Display` writes it.
pub fn push_time(t: f64, out: &mut Vec<u8>) {
    write!(out, "{}", output_time(t)).expect("writing to a vector");
}

/// Appends the text of a value: the shortest that reads back to the same double.
pub fn push_value(v: f64, out: &mut Vec<u8>) {
    if v.is_finite() {
        out.extend_from_slice(zmij::Buffer::new().format_finite(v).as_bytes());
    } else {
        write!(out, "{v}").expect("writing to a vector");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rounded times read as their 12-digit text, and every value's text reads back to its
    /// bits (signed zeros, subnormals, extremes).
    #[test]
    fn times_round_to_twelve_digits_and_values_read_back_exactly() {
        assert_eq!(output_time(3.0300000000000002), 3.03);
        assert_eq!(output_time(0.1 + 0.2), 0.3);
        assert_eq!(output_time(-1.0 / 3.0), -0.333333333333);
        let mut text = Vec::new();
        push_time(0.005 * 7.0, &mut text);
        assert_eq!(text, b"0.035");
        for v in [
            0.0,
            -0.0,
            1.5e-7,
            0.25,
            -3.0,
            f64::MIN_POSITIVE,
            5e-324,
            f64::MAX,
            1.0 / 3.0,
        ] {
            let mut text = Vec::new();
            push_value(v, &mut text);
            let back: f64 = std::str::from_utf8(&text).unwrap().parse().unwrap();
            assert_eq!(back.to_bits(), v.to_bits(), "{v:e}");
        }
        let mut text = Vec::new();
        push_value(1.5e-7, &mut text);
        assert_eq!(text, b"1.5e-7");
    }
}
