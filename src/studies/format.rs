//! Numbers as text for the studies' reports and figures.

/// `v` with `sig` significant digits, plain or scientific as suits its size.
pub fn sig(v: f64, sig: usize) -> String {
    if !v.is_finite() {
        return if v.is_nan() { "-".into() } else { format!("{v}") };
    }
    if v == 0.0 {
        return "0".into();
    }
    let mag = v.abs().log10().floor() as i32;
    if !(-3..6).contains(&mag) {
        return format!("{:.*e}", sig.saturating_sub(1), v);
    }
    let decimals = (sig as i32 - 1 - mag).max(0) as usize;
    format!("{v:.decimals$}")
}

/// `v` with `decimals` decimals (`{:.decimals$}`), or in exponent form from `1e15` in
/// magnitude, where the fixed form would print every digit of the integer part.
pub fn fixed(v: f64, decimals: usize) -> String {
    if v.abs() < 1e15 { format!("{v:.decimals$}") } else { format!("{v:.decimals$e}") }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn significant_digits() {
        assert_eq!(sig(0.012345, 3), "0.0123");
        assert_eq!(sig(123.456, 3), "123");
        assert_eq!(sig(-1.5, 2), "-1.5");
        assert_eq!(sig(1.23e-7, 2), "1.2e-7");
        assert_eq!(sig(f64::NAN, 2), "-");
    }

    #[test]
    fn fixed_keeps_large_numbers_short() {
        assert_eq!(fixed(0.5, 6), "0.500000");
        assert_eq!(fixed(-123.25, 2), "-123.25");
        assert_eq!(fixed(7.1e299, 6), "7.100000e299");
        assert_eq!(fixed(f64::NAN, 3), "NaN");
    }
}
