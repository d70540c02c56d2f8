//! Numbers in messages: readable at any magnitude (`3.92e302`, not 300
//! digits; `1.5e-12`, not `0.000000`), and a breached bound printed with
//! enough significant digits that the value visibly differs from the bound.

/// `v` with at most `sig` significant digits: plain decimals for
/// 1e-3 ≤ |v| < 1e6, else scientific notation (`1.5e-12`, `3.92e302`);
/// trailing zeros are dropped.
pub fn with_digits(v: f64, sig: usize) -> String {
    if v.is_nan() {
        return "NaN".into();
    }
    if v.is_infinite() {
        return if v > 0.0 { "inf" } else { "-inf" }.into();
    }
    if v == 0.0 {
        return "0".into();
    }
    let sig = sig.clamp(1, 17);
    let a = v.abs();
    if (1e-3..1e6).contains(&a) {
        // Digits after the point for `sig` significant digits.
        let exp = a.log10().floor() as i32;
        let decimals = (sig as i32 - 1 - exp).max(0) as usize;
        let s = format!("{v:.decimals$}");
        // Rounding may carry into a new digit (999999.5 → 1000000): fine.
        trim(&s)
    } else {
        let s = format!("{v:.prec$e}", prec = sig - 1);
        match s.split_once('e') {
            Some((m, e)) => format!("{}e{e}", trim(m)),
            None => s,
        }
    }
}

/// Drops trailing zeros after a decimal point (and the point itself).
fn trim(s: &str) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s.to_string()
    }
}

/// `v` readably, with 4 significant digits.
pub fn readable(v: f64) -> String {
    with_digits(v, 4)
}

/// The shortest text that reads back as `v` (`1e-9`, `0.089`, `2e6`).
pub fn shortest(v: f64) -> String {
    let a = v.abs();
    if v.is_finite() && v != 0.0 && !(1e-3..1e6).contains(&a) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// Numbers as a TOML array writes them: `[0.1, 2, 1e-9]`.
pub fn list(v: &[f64]) -> String {
    let items: Vec<String> = v.iter().map(|x| shortest(*x)).collect();
    format!("[{}]", items.join(", "))
}

/// A value and the bound it breached, each with the fewest significant
/// digits (at least 3) at which the two print differently, so a message
/// such as `x = 1.0000002e-9 > 1e-9` shows the breach.
pub fn breach(value: f64, bound: f64) -> (String, String) {
    for sig in 3..=17 {
        let (a, b) = (with_digits(value, sig), with_digits(bound, sig));
        if a != b || sig == 17 {
            return (a, shortest(bound));
        }
    }
    unreachable!("the loop returns at sig = 17")
}

/// `text` with every number written out in 20 or more digits (what `{}`
/// makes of 1e300 or 1e-300, in messages of other crates such as serde's
/// `invalid type: floating point ...`) in its [`readable`] form. Digits that
/// continue a word, a path or a name (`w_123...`, `/tmp/123...`) are left
/// alone.
pub fn shorten_long_numbers(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    let mut copied = 0;
    while i < b.len() {
        let starts = b[i].is_ascii_digit()
            && (i == 0
                || !(b[i - 1].is_ascii_alphanumeric() || matches!(b[i - 1], b'_' | b'/' | b'.')));
        if !starts {
            i += 1;
            continue;
        }
        let mut j = i;
        while j < b.len() && b[j].is_ascii_digit() {
            j += 1;
        }
        if j + 1 < b.len() && b[j] == b'.' && b[j + 1].is_ascii_digit() {
            j += 1;
            while j < b.len() && b[j].is_ascii_digit() {
                j += 1;
            }
        }
        let word_follows = j < b.len() && (b[j].is_ascii_alphanumeric() || b[j] == b'_');
        let digits = text[i..j].bytes().filter(u8::is_ascii_digit).count();
        if digits >= 20 && !word_follows {
            if let Ok(v) = text[i..j].parse::<f64>() {
                out.push_str(&text[copied..i]);
                out.push_str(&readable(v));
                copied = j;
            }
        }
        i = j;
    }
    out.push_str(&text[copied..]);
    out
}

/// A metric value for tables.
pub(crate) fn fmt_value(v: f64) -> String {
    if v.is_nan() {
        "NaN".into()
    } else if v == 0.0 || (v.abs() >= 1e-3 && v.abs() < 1e6) {
        format!("{v:.6}")
    } else {
        format!("{v:.4e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn readable_at_every_magnitude() {
        assert_eq!(readable(0.0), "0");
        assert_eq!(readable(1.5e-12), "1.5e-12");
        assert_eq!(readable(3.919_688_894_629_128e302), "3.92e302");
        assert_eq!(readable(4.376), "4.376");
        assert_eq!(readable(17.748), "17.75");
        assert_eq!(readable(2_000_000.0), "2e6");
        assert_eq!(readable(-0.0025), "-0.0025");
        assert_eq!(readable(f64::NAN), "NaN");
        assert_eq!(readable(f64::INFINITY), "inf");
        assert!(readable(1e300).len() < 10);
    }

    #[test]
    fn long_numbers_in_other_crates_messages_are_shortened() {
        let long = format!("{}", 1e300);
        let tiny = format!("{}", 1e-300);
        assert!(long.len() > 300 && tiny.len() > 300);
        assert_eq!(
            shorten_long_numbers(&format!(
                "invalid type: floating point `{long}`, expected u32"
            )),
            "invalid type: floating point `1e300`, expected u32"
        );
        assert_eq!(
            shorten_long_numbers(&format!("got -{tiny} s")),
            "got -1e-300 s"
        );
        // Names, paths and ordinary numbers are left alone.
        for keep in [
            "/tmp/w25051_89210404934969458471234/x.toml:38: key `a`: got 0.5",
            "/tmp/12345678901234567890123/case.toml",
            "run 123456789012345678901234abc",
            "3.14159 and 2e6",
        ] {
            assert_eq!(shorten_long_numbers(keep), keep);
        }
    }

    #[test]
    fn breach_shows_the_difference() {
        // The case: a real failure printed as `0.000000 > 0.00000000000001`.
        let (v, b) = breach(3.2e-13, 1e-14);
        assert_eq!((v.as_str(), b.as_str()), ("3.2e-13", "1e-14"));
        // Close to the bound: more digits until they differ.
        let (v, b) = breach(1.000_000_2e-9, 1e-9);
        assert_eq!((v.as_str(), b.as_str()), ("1.0000002e-9", "1e-9"));
        let (v, b) = breach(0.0031, 0.003);
        assert_eq!((v.as_str(), b.as_str()), ("0.0031", "0.003"));
        let (v, _) = breach(0.003_000_001, 0.003);
        assert_ne!(v.parse::<f64>().unwrap(), 0.003);
        // The bound is printed exactly as far as f64 allows.
        let (_, b) = breach(2.0, 0.089);
        assert_eq!(b, "0.089");
        assert_eq!(breach(f64::NAN, 1.0).0, "NaN");
    }
}
