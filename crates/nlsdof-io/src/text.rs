//! Text from input files as it may appear in a message: the one place that
//! escapes bytes (issue 30: a gzip header, binary garbage or UTF-16 text
//! reached the terminal raw, NUL bytes and line separators included), and
//! the one test of whether a file is text at all.

/// At most this many characters of file content are quoted in a message.
pub const SHOWN_CHARS: usize = 60;

/// `s` as a message may quote it: control and invisible format characters
/// (NUL, line and paragraph separators, the replacement character of a
/// lossy decoding, ...) escaped as `\u{..}`, tabs as `\t`, and at most
/// [`SHOWN_CHARS`] characters (then `...`). Always one line.
pub fn shown(s: &str) -> String {
    let mut out = String::new();
    for (n, c) in s.chars().enumerate() {
        if n == SHOWN_CHARS {
            out.push_str("...");
            break;
        }
        match c {
            '\t' => out.push_str("\\t"),
            c if c.is_control()
                || matches!(c, '\u{2028}' | '\u{2029}' | '\u{feff}' | '\u{fffd}' | '\u{200b}'..='\u{200f}' | '\u{202a}'..='\u{202e}') =>
            {
                out.push_str(&format!("\\u{{{:x}}}", c as u32))
            }
            c => out.push(c),
        }
    }
    out
}

/// What a file is when it is not a text table, from its first bytes:
/// `Some(description)` for compressed, archive, MAT or UTF-16 files and for
/// anything with a NUL byte in its first 4 KiB; `None` for text.
pub fn not_text(bytes: &[u8]) -> Option<String> {
    let head = &bytes[..bytes.len().min(4096)];
    if head.starts_with(&[0x1f, 0x8b]) {
        return Some("gzip-compressed data (decompress it first)".into());
    }
    if head.starts_with(b"PK\x03\x04") {
        return Some("a zip archive (extract the table first)".into());
    }
    if head.starts_with(b"MATLAB 5.0 MAT-file") {
        return Some(
            "a MATLAB MAT-file, not a text table (export the columns as CSV, e.g. with scipy.io.loadmat)"
                .into(),
        );
    }
    if head.starts_with(&[0xff, 0xfe]) || head.starts_with(&[0xfe, 0xff]) {
        return Some("UTF-16 text (save it as UTF-8)".into());
    }
    let nul = head.iter().position(|&b| b == 0)?;
    // ASCII in UTF-16: every other byte NUL
    let utf16 = head.len() >= 8
        && head
            .chunks(2)
            .take(64)
            .filter(|p| p.len() == 2 && (p[0] == 0) != (p[1] == 0))
            .count()
            * 10
            >= head.chunks(2).take(64).count() * 9;
    Some(if utf16 {
        "UTF-16 text without a byte-order mark (save it as UTF-8)".into()
    } else {
        format!("binary data (a NUL byte at offset {nul}), not a text table")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shown_is_one_short_line_of_printable_text() {
        assert_eq!(shown("V1"), "V1");
        assert_eq!(
            shown("a\0b\nc\u{2028}d\te\u{fffd}"),
            "a\\u{0}b\\u{a}c\\u{2028}d\\te\\u{fffd}"
        );
        let long = "x".repeat(500);
        assert_eq!(shown(&long).chars().count(), SHOWN_CHARS + 3);
        assert_eq!(shown("µs, °C"), "µs, °C");
    }

    #[test]
    fn binary_files_are_told_apart_from_text() {
        assert!(not_text(b"t,x\n0,1\n").is_none());
        assert!(not_text("µ,°\n1,2\n".as_bytes()).is_none());
        assert!(not_text(&[0x1f, 0x8b, 8, 0]).unwrap().contains("gzip"));
        assert!(not_text(b"MATLAB 5.0 MAT-file, Platform")
            .unwrap()
            .contains("MAT-file"));
        assert!(not_text(&[0xff, 0xfe, b't', 0]).unwrap().contains("UTF-16"));
        let utf16: Vec<u8> = "t,x\n0,1\n".bytes().flat_map(|b| [b, 0]).collect();
        assert!(not_text(&utf16).unwrap().contains("UTF-16"));
        assert!(not_text(&[1, 2, 0, 200, 7, 9, 9, 9, 9, 9])
            .unwrap()
            .contains("NUL"));
    }
}
