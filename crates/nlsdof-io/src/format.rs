//! What a data file is, from its first bytes (magic numbers, first lines)
//! and, only where the content cannot tell, its name: the detection under
//! [`crate::input`] (the reader layer) and [`crate::text`] (text files read
//! whole). A leaf module: it uses no other module of the crate, so every
//! reader can ask it.

use std::path::Path;

/// What a data file is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Format {
    /// Delimited text (comma, semicolon, tab or spaces).
    Csv,
    /// LabVIEW measurement text (`.lvm`).
    Lvm,
    /// Polytec ASCII export (a preamble, a header, a `[ unit ]` line).
    Polytec,
    /// MATLAB MAT-file (v5; v4 and v7.3 are recognised and refused by the
    /// MAT reader with their own message).
    Mat,
    /// Universal file, dataset 58 (ASCII) or 58b (binary).
    Uff,
    /// Not text and none of the above: what it is and what to do.
    Other(String),
}

impl Format {
    /// The format's name in a message.
    pub fn name(&self) -> &str {
        match self {
            Format::Csv => "a CSV (delimited text) table",
            Format::Lvm => "a LabVIEW measurement (.lvm) file",
            Format::Polytec => "a Polytec ASCII export",
            Format::Mat => "a MATLAB MAT-file",
            Format::Uff => "a universal file (dataset 58)",
            Format::Other(what) => what,
        }
    }
}

/// Bytes looked at to decide the format.
pub const HEAD_BYTES: usize = 4096;

fn ext_is(path: &Path, exts: &[&str]) -> bool {
    path.extension()
        .map(|e| exts.iter().any(|x| e.eq_ignore_ascii_case(x)))
        .unwrap_or(false)
}

/// Whether `head` starts like an ASCII universal file: a line `-1`, then a
/// line holding a dataset number (`58`, `58b`, `151`, ...).
fn looks_uff(head: &[u8]) -> bool {
    let mut lines = head
        .split(|&b| b == b'\n')
        .map(|l| l.trim_ascii())
        .filter(|l| !l.is_empty());
    if lines.next() != Some(&b"-1"[..]) {
        return false;
    }
    match lines.next() {
        Some(l) => {
            let tok = l.split(|b| b.is_ascii_whitespace()).next().unwrap_or(b"");
            let digits = tok.strip_suffix(b"b").unwrap_or(tok);
            !digits.is_empty() && digits.len() <= 6 && digits.iter().all(u8::is_ascii_digit)
        }
        None => false,
    }
}

/// The format of a file from its first bytes `head` (at least
/// [`HEAD_BYTES`] of them when the file is that long) and its name. Never
/// panics, whatever the bytes.
pub fn detect(head: &[u8], path: &Path) -> Format {
    let head = &head[..head.len().min(HEAD_BYTES)];
    if head.starts_with(b"MATLAB 5.0 MAT-file") || head.starts_with(b"MATLAB 7.3 MAT-file") {
        return Format::Mat;
    }
    if looks_uff(head) {
        return Format::Uff;
    }
    if let Some(what) = not_text(head) {
        // MAT v4 has no magic; a binary universal file starts with text
        // but the extension is what a lab names it by
        if ext_is(path, &["mat"]) && !what.contains("compressed") && !what.contains("archive") {
            return Format::Mat;
        }
        if ext_is(path, &["uff", "unv"]) {
            return Format::Uff;
        }
        return Format::Other(what);
    }
    if ext_is(path, &["uff", "unv"]) {
        return Format::Uff;
    }
    // a text file named .mat is not a table someone meant: the MAT reader
    // says it has no MAT header
    if ext_is(path, &["mat"]) {
        return Format::Mat;
    }
    let text = String::from_utf8_lossy(head);
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    if text.starts_with("LabVIEW Measurement") {
        return Format::Lvm;
    }
    if text.starts_with("Source File Name") {
        return Format::Polytec;
    }
    Format::Csv
}

/// When `bytes` (a file's first bytes at least) are not a text table:
/// the detected format and what to do, for a message.
pub fn not_text_format(bytes: &[u8], path: &Path) -> Option<String> {
    let binary = not_text(&bytes[..bytes.len().min(HEAD_BYTES)])?;
    Some(match detect(bytes, path) {
        Format::Mat => "a MATLAB MAT-file, not a text table: this verb reads CSV text (the time-history verbs read MAT variables by name with --column)".into(),
        Format::Uff => "a binary universal file (dataset 58b), not a text table: give it a .uff or .unv name".into(),
        _ => binary,
    })
}

/// The format of the file at `path` ([`detect`] on its first bytes).
pub fn detect_file(path: &Path) -> std::io::Result<Format> {
    use std::io::Read;
    let mut head = Vec::with_capacity(HEAD_BYTES);
    std::fs::File::open(path)?
        .take(HEAD_BYTES as u64)
        .read_to_end(&mut head)?;
    Ok(detect(&head, path))
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
