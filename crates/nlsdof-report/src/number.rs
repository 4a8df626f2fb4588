//! Numbers in text output and in one-line error messages.

/// A number for text output and messages: the shortest form that reads back
/// to the same `f64`, in exponent notation outside `1e-4 <= |v| < 1e15`
/// (so `1e308` is `1e308`, not 309 digits). JSON and CSV keep their own
/// full-precision formatting.
pub fn num(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || !v.is_finite() || (1e-4..1e15).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Rewrites every long decimal number (more than 17 characters, as Rust's
/// `{}` prints 1e308 or 1e-300) in a message with [`num`].
pub fn compact_numbers(msg: &str) -> String {
    let b = msg.as_bytes();
    let mut out = String::with_capacity(msg.len());
    let mut i = 0;
    while i < b.len() {
        let starts_number = b[i].is_ascii_digit()
            && (i == 0
                || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'.' || b[i - 1] == b'_'));
        if starts_number {
            let mut j = i;
            while j < b.len() && (b[j].is_ascii_digit() || b[j] == b'.') {
                j += 1;
            }
            let tok = &msg[i..j];
            let ends_clean = j == b.len() || !(b[j].is_ascii_alphanumeric() || b[j] == b'_');
            if tok.len() > 17 && ends_clean {
                if let Ok(v) = tok.trim_end_matches('.').parse::<f64>() {
                    out.push_str(&num(v));
                    if tok.ends_with('.') {
                        out.push('.');
                    }
                    i = j;
                    continue;
                }
            }
            out.push_str(tok);
            i = j;
            continue;
        }
        let ch = msg[i..].chars().next().unwrap_or(' ');
        out.push(ch);
        i += ch.len_utf8();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_numbers_are_compacted() {
        let big = format!("--gamma {} is not allowed", -1e308);
        assert_eq!(compact_numbers(&big), "--gamma -1e308 is not allowed");
        let small = format!("at amplitude {} m", 2.5e-200);
        assert_eq!(compact_numbers(&small), "at amplitude 2.5e-200 m");
        let keep = "line 12: 0.41 and 123456 and file_20260101123456789012.csv";
        assert_eq!(compact_numbers(keep), keep);
        assert_eq!(num(0.41), "0.41");
        assert_eq!(num(1e308), "1e308");
        assert_eq!(num(2533030720596579e96), "2.533030720596579e111");
    }
}
