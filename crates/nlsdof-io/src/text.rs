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

pub use crate::format::not_text;

/// Largest text file read whole (the stepped-sine, phase-resonance and FRF
/// tables and the CSV/Polytec time histories of `frf-estimate`): 256 MiB.
/// These are held in memory with every parsed value, so a larger file is
/// refused rather than risk exhausting memory; the streamed readers
/// (`decay`, `fit-time`, `simulate`, `spectrogram`) take larger tables.
pub const MAX_TEXT_BYTES: u64 = 256 << 20;

/// Why a text file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum TextFileError {
    #[error("cannot read: {0}")]
    Read(#[from] std::io::Error),
    #[error("the file has {bytes} bytes; a table read whole is at most {max} bytes (256 MiB, held in memory while parsed): split it or keep only the rows needed", max = MAX_TEXT_BYTES)]
    TooLarge { bytes: u64 },
    /// Binary, compressed, MAT, UTF-16: what it is (never its bytes).
    #[error("this is {0}")]
    NotText(String),
}

/// Windows-1252 characters of the bytes 0x80–0x9F (the C1 controls where
/// the code page leaves a byte undefined, as the WHATWG decoder does).
const CP1252: [char; 32] = [
    '\u{20ac}', '\u{81}', '\u{201a}', '\u{192}', '\u{201e}', '\u{2026}', '\u{2020}', '\u{2021}',
    '\u{2c6}', '\u{2030}', '\u{160}', '\u{2039}', '\u{152}', '\u{8d}', '\u{17d}', '\u{8f}',
    '\u{90}', '\u{2018}', '\u{2019}', '\u{201c}', '\u{201d}', '\u{2022}', '\u{2013}', '\u{2014}',
    '\u{2dc}', '\u{2122}', '\u{161}', '\u{203a}', '\u{153}', '\u{9d}', '\u{17e}', '\u{178}',
];

/// `bytes` as text: UTF-8 when they are, else Windows-1252 (a superset of
/// Latin-1 for printable text: `µ`, `°`, `²` of a European lab export).
/// Every byte sequence decodes; nothing is lost or replaced.
pub fn decode(bytes: &[u8]) -> std::borrow::Cow<'_, str> {
    match std::str::from_utf8(bytes) {
        Ok(s) => std::borrow::Cow::Borrowed(s),
        Err(_) => std::borrow::Cow::Owned(
            bytes
                .iter()
                .map(|&b| match b {
                    0x80..=0x9f => CP1252[(b - 0x80) as usize],
                    b => b as char,
                })
                .collect(),
        ),
    }
}

/// The text of the file at `path` ([`decode`]d), refusing files larger
/// than [`MAX_TEXT_BYTES`] and files that are not text ([`not_text`]).
pub fn read_text(path: &std::path::Path) -> Result<String, TextFileError> {
    use std::io::Read;
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(MAX_TEXT_BYTES + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > MAX_TEXT_BYTES {
        let bytes = std::fs::metadata(path)
            .map(|m| m.len())
            .unwrap_or(bytes.len() as u64);
        return Err(TextFileError::TooLarge { bytes });
    }
    if let Some(what) = crate::format::not_text_format(&bytes, path) {
        return Err(TextFileError::NotText(what));
    }
    Ok(decode(&bytes).into_owned())
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
    fn latin1_and_windows1252_are_decoded() {
        // "µm" and "°C" in Latin-1, "€" and "–" in Windows-1252
        assert_eq!(decode(b"Amp \xb5m, T \xb0C"), "Amp µm, T °C");
        assert_eq!(decode(b"\x80 \x96"), "€ –");
        assert_eq!(decode("µ".as_bytes()), "µ");
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
