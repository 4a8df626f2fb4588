//! The CSV reader of the table formats, built on the `csv` crate: rows
//! streamed one at a time with their line numbers, fields trimmed, blank
//! lines and `#` comment lines skipped, a leading UTF-8 byte-order mark
//! dropped (Excel writes one), columns found by header name
//! (case-insensitive), and optionally decimal commas (fields then separated
//! by `;`). Fields are split at the separator without quoting, like the
//! hand-written readers it replaces.

use std::io::Read;

/// How the text is laid out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CsvOptions {
    /// Numbers written with a decimal comma (`1,5`); fields separated by `;`.
    pub decimal_comma: bool,
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
            CsvReadError::Utf8 { .. } => write!(f, "stream did not contain valid UTF-8"),
        }
    }
}

impl std::error::Error for CsvReadError {}

/// A streaming reader of the data rows (and the header, which is just the
/// first row).
pub struct CsvRows<R: Read> {
    rdr: csv::Reader<R>,
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
            .delimiter(if options.decimal_comma { b';' } else { b',' })
            .buffer_capacity(1 << 20)
            .from_reader(read);
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
                let text = std::str::from_utf8(raw).map_err(|_| CsvReadError::Utf8 { line })?;
                self.fields.push(text.to_string());
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
        let mut r = CsvRows::new(
            text.as_bytes(),
            CsvOptions {
                decimal_comma: true,
            },
        );
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
}
