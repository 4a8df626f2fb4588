//! The one CSV reader of every text format, built on the `csv` crate: rows
//! streamed one at a time with their line numbers, fields trimmed, blank
//! lines and `#` comment lines skipped, a leading UTF-8 byte-order mark
//! dropped (Excel writes one), columns found by header name
//! (case-insensitive), and optionally decimal commas. Fields are split at
//! the [`Separator`] without quoting. The instrument exports use it too:
//! Polytec (tab-separated, latin-1, decimal commas), LabVIEW `.lvm`
//! (tab-separated), time histories separated by commas, semicolons or
//! whitespace.

use std::io::Read;

/// How the fields of a line are separated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Separator {
    /// `,`, or `;` when numbers have decimal commas.
    #[default]
    Standard,
    Comma,
    Semicolon,
    Tab,
    /// Decided line by line: `,` if the line has one, else `;` if it has
    /// one, else runs of whitespace (the time-history exports).
    PerLine,
}

/// How bytes become text.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Encoding {
    /// UTF-8; a line that is not is an error.
    #[default]
    Utf8,
    /// UTF-8, invalid bytes replaced by U+FFFD.
    Utf8Lossy,
    /// ISO 8859-1 (Polytec exports): every byte is a character.
    Latin1,
}

/// How the text is laid out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CsvOptions {
    /// Numbers written with a decimal comma (`1,5`); with
    /// [`Separator::Standard`] fields are then separated by `;`.
    pub decimal_comma: bool,
    pub separator: Separator,
    pub encoding: Encoding,
}

impl CsvOptions {
    /// The options with `separator`.
    pub fn with_separator(mut self, separator: Separator) -> Self {
        self.separator = separator;
        self
    }
    /// The options with `encoding`.
    pub fn with_encoding(mut self, encoding: Encoding) -> Self {
        self.encoding = encoding;
        self
    }
    /// The options with decimal commas.
    pub fn with_decimal_comma(mut self) -> Self {
        self.decimal_comma = true;
        self
    }
}

/// Why a row could not be read.
#[derive(Debug)]
pub enum CsvReadError {
    /// The underlying reader failed.
    Io(std::io::Error),
    /// A line is not UTF-8.
    Utf8 { line: u64 },
}

impl std::fmt::Display for CsvReadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CsvReadError::Io(e) => write!(f, "{e}"),
            CsvReadError::Utf8 { line } => write!(
                f,
                "line {line} is not UTF-8 text (a Latin-1 or Windows-1252 file? save it as UTF-8)"
            ),
        }
    }
}

impl std::error::Error for CsvReadError {}

/// The csv crate skips empty lines and then reports the next record at
/// the empty line's number. This adapter writes a space into every empty
/// line, so that each line is a record and the line numbers stay right (a
/// blank record is skipped by [`CsvRows::next_row`]).
struct KeepBlankLines<R> {
    inner: R,
    buf: Vec<u8>,
    pos: usize,
    at_line_start: bool,
}

impl<R: Read> KeepBlankLines<R> {
    fn new(inner: R) -> Self {
        Self {
            inner,
            buf: Vec::new(),
            pos: 0,
            at_line_start: true,
        }
    }
}

impl<R: Read> Read for KeepBlankLines<R> {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        if self.pos == self.buf.len() {
            let mut raw = [0u8; 1 << 16];
            let n = self.inner.read(&mut raw)?;
            if n == 0 {
                return Ok(0);
            }
            self.buf.clear();
            self.pos = 0;
            for &b in &raw[..n] {
                if b == b'\n' && self.at_line_start {
                    self.buf.push(b' ');
                }
                self.buf.push(b);
                self.at_line_start = b == b'\n';
            }
        }
        let k = (self.buf.len() - self.pos).min(out.len());
        out[..k].copy_from_slice(&self.buf[self.pos..self.pos + k]);
        self.pos += k;
        Ok(k)
    }
}

/// A streaming reader of the data rows (and the header, which is just the
/// first row).
pub struct CsvRows<R: Read> {
    rdr: csv::Reader<KeepBlankLines<R>>,
    rec: csv::ByteRecord,
    fields: Vec<String>,
    first: bool,
    options: CsvOptions,
}

impl<R: Read> CsvRows<R> {
    pub fn new(read: R, options: CsvOptions) -> Self {
        let rdr = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .quoting(false)
            // lines end at '\n' only (a '\r' before it is trimmed), as `str::lines`
            .terminator(csv::Terminator::Any(b'\n'))
            .delimiter(match options.separator {
                Separator::Standard if options.decimal_comma => b';',
                Separator::Standard | Separator::Comma => b',',
                Separator::Semicolon => b';',
                Separator::Tab => b'\t',
                // the whole line is one record field, split in `next_row`
                Separator::PerLine => b'\0',
            })
            .buffer_capacity(1 << 20)
            .from_reader(KeepBlankLines::new(read));
        Self {
            rdr,
            rec: csv::ByteRecord::new(),
            fields: Vec::new(),
            first: true,
            options,
        }
    }

    /// The next row that is not blank and not a `#` comment: its line
    /// number (1-based) and its trimmed fields.
    pub fn next_row(&mut self) -> Result<Option<(u64, &[String])>, CsvReadError> {
        loop {
            let more = self.rdr.read_byte_record(&mut self.rec).map_err(|e| {
                let line = e.position().map(|p| p.line()).unwrap_or(0);
                match e.into_kind() {
                    csv::ErrorKind::Io(io) => CsvReadError::Io(io),
                    _ => CsvReadError::Utf8 { line },
                }
            })?;
            if !more {
                return Ok(None);
            }
            let line = self.rec.position().map(|p| p.line()).unwrap_or(0);
            self.fields.clear();
            for raw in self.rec.iter() {
                let text = match self.options.encoding {
                    Encoding::Utf8 => std::str::from_utf8(raw)
                        .map_err(|_| CsvReadError::Utf8 { line })?
                        .to_string(),
                    Encoding::Utf8Lossy => String::from_utf8_lossy(raw).into_owned(),
                    Encoding::Latin1 => raw.iter().map(|&b| b as char).collect(),
                };
                if self.options.separator == Separator::PerLine {
                    let text = text.trim_end_matches('\r');
                    if text.contains(',') {
                        self.fields.extend(text.split(',').map(str::to_string));
                    } else if text.contains(';') {
                        self.fields.extend(text.split(';').map(str::to_string));
                    } else {
                        self.fields
                            .extend(text.split_whitespace().map(str::to_string));
                    }
                } else {
                    self.fields.push(text);
                }
            }
            if std::mem::take(&mut self.first) {
                if let Some(f) = self.fields.first_mut() {
                    if let Some(rest) = f.strip_prefix('\u{feff}') {
                        *f = rest.to_string();
                    }
                }
            }
            for f in self.fields.iter_mut() {
                let t = f.trim();
                if t.len() != f.len() {
                    *f = t.to_string();
                }
            }
            let blank = self.fields.len() <= 1 && self.fields.iter().all(|f| f.is_empty());
            let comment = self.fields.first().is_some_and(|f| f.starts_with('#'));
            if !(blank || comment) {
                return Ok(Some((line, &self.fields)));
            }
        }
    }

    /// `field` as a number (with a decimal comma if so configured); `None`
    /// if it is not one.
    pub fn number(&self, field: &str) -> Option<f64> {
        number(field, self.options)
    }
}

/// `field` as a number (with a decimal comma if `options` says so).
pub fn number(field: &str, options: CsvOptions) -> Option<f64> {
    if options.decimal_comma {
        field.replace(',', ".").parse().ok()
    } else {
        field.parse().ok()
    }
}

/// One data row of a table whose header names `width` columns: fields by
/// column index, with the messages of the table readers (the caller adds
/// file and line).
pub struct Row<'a> {
    fields: &'a [String],
}

impl<'a> Row<'a> {
    /// `fields`, at most `width` of them (a missing trailing field is
    /// reported when asked for).
    pub fn new(fields: &'a [String], width: usize) -> Result<Self, String> {
        if fields.len() > width {
            return Err(format!(
                "{} fields, but the header names {width} columns",
                fields.len()
            ));
        }
        Ok(Self { fields })
    }

    /// Field `c`, named `name` in the message if it is missing.
    pub fn field(&self, c: usize, name: &str) -> Result<&'a str, String> {
        self.fields
            .get(c)
            .map(String::as_str)
            .ok_or_else(|| format!("missing field '{name}'"))
    }

    /// Field `c` as a number.
    pub fn number(&self, c: usize, name: &str) -> Result<f64, String> {
        let s = self.field(c, name)?;
        s.parse::<f64>()
            .map_err(|_| format!("{name} = '{s}' is not a number"))
    }
}

/// The header's names in lower case.
pub fn lowercase(header: &[String]) -> Vec<String> {
    header.iter().map(|c| c.to_ascii_lowercase()).collect()
}

/// Index of the header name `name` (case-insensitive) among `header`.
pub fn column(header: &[String], name: &str) -> Option<usize> {
    header.iter().position(|h| h.eq_ignore_ascii_case(name))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn skips_comments_blanks_and_bom_and_reads_decimal_commas() {
        let text = "\u{feff}T ; X\n# a comment\n\n   \n  # indented comment\n0;1,5\n1 ; -2,25\n";
        let mut r = CsvRows::new(text.as_bytes(), CsvOptions::default().with_decimal_comma());
        let (line, header) = r.next_row().unwrap().unwrap();
        assert_eq!(
            (line, header.to_vec()),
            (1, vec!["T".to_string(), "X".into()])
        );
        assert_eq!(column(header, "x"), Some(1));
        let (line, row) = r.next_row().unwrap().unwrap();
        let row = row.to_vec();
        assert_eq!(line, 6);
        assert_eq!(r.number(&row[1]), Some(1.5));
        let (line, row) = r.next_row().unwrap().unwrap();
        let row = row.to_vec();
        assert_eq!((line, r.number(&row[1])), (7, Some(-2.25)));
        assert!(r.next_row().unwrap().is_none());
    }

    #[test]
    fn lines_end_at_newline_only() {
        let mut r = CsvRows::new("a,b\r\n1\r2,3\r\n".as_bytes(), CsvOptions::default());
        assert_eq!(r.next_row().unwrap().unwrap().1, ["a", "b"]);
        let (line, row) = r.next_row().unwrap().unwrap();
        assert_eq!((line, row), (2, &["1\r2".to_string(), "3".to_string()][..]));
    }

    #[test]
    fn splits_without_quoting() {
        let mut r = CsvRows::new("a,\"b\n1,2\n".as_bytes(), CsvOptions::default());
        assert_eq!(r.next_row().unwrap().unwrap().1, ["a", "\"b"]);
        assert_eq!(r.next_row().unwrap().unwrap().1, ["1", "2"]);
    }

    #[test]
    fn tab_latin1_and_decimal_commas_together() {
        // "µ" is 0xB5 in latin-1: not UTF-8
        let bytes = b"Freq\tAmp \xb5m\n1,5\t-2,25\n";
        let opts = CsvOptions::default()
            .with_separator(Separator::Tab)
            .with_encoding(Encoding::Latin1)
            .with_decimal_comma();
        let mut r = CsvRows::new(&bytes[..], opts);
        assert_eq!(r.next_row().unwrap().unwrap().1, ["Freq", "Amp \u{b5}m"]);
        let row = r.next_row().unwrap().unwrap().1.to_vec();
        assert_eq!(
            (r.number(&row[0]), r.number(&row[1])),
            (Some(1.5), Some(-2.25))
        );
        // the same bytes as UTF-8 are refused, with the line
        let mut r = CsvRows::new(&bytes[..], opts.with_encoding(Encoding::Utf8));
        assert!(matches!(r.next_row(), Err(CsvReadError::Utf8 { line: 1 })));
        // and read lossily
        let mut r = CsvRows::new(&bytes[..], opts.with_encoding(Encoding::Utf8Lossy));
        assert_eq!(r.next_row().unwrap().unwrap().1, ["Freq", "Amp \u{fffd}m"]);
    }

    #[test]
    fn per_line_separator_and_bom() {
        let text = "\u{feff}t x y\n0,1,2\n1;3;4\n 2  5\t6 \r\n";
        let opts = CsvOptions::default().with_separator(Separator::PerLine);
        let mut r = CsvRows::new(text.as_bytes(), opts);
        assert_eq!(r.next_row().unwrap().unwrap().1, ["t", "x", "y"]);
        assert_eq!(r.next_row().unwrap().unwrap().1, ["0", "1", "2"]);
        assert_eq!(r.next_row().unwrap().unwrap().1, ["1", "3", "4"]);
        let (line, row) = r.next_row().unwrap().unwrap();
        assert_eq!(
            (line, row),
            (4, &["2".to_string(), "5".into(), "6".into()][..])
        );
        assert!(r.next_row().unwrap().is_none());
    }

    #[test]
    fn line_numbers_count_empty_lines() {
        // the csv crate alone reports "b" at line 2 and "d" at line 5
        let text = "a\n\nb\n\n\n\nd\n";
        let mut r = CsvRows::new(text.as_bytes(), CsvOptions::default());
        assert_eq!(r.next_row().unwrap().unwrap().0, 1);
        assert_eq!(r.next_row().unwrap().unwrap().0, 3);
        let (line, row) = r.next_row().unwrap().unwrap();
        assert_eq!((line, row), (7, &["d".to_string()][..]));
        assert!(r.next_row().unwrap().is_none());
        // also when the file starts with an empty line
        let mut r = CsvRows::new("\nx,y\n".as_bytes(), CsvOptions::default());
        assert_eq!(r.next_row().unwrap().unwrap().0, 2);
    }
}
