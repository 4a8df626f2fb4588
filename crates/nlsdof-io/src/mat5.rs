//! A small, bounded reader of MATLAB MAT v5 (`-v6`/`-v7`) files: the real
//! numeric arrays of a file, converted to `f64`.
//!
//! Written for robustness rather than completeness: every length is checked
//! against the bytes present before anything is allocated, compressed
//! elements (`-v7`) are inflated with a limit on the total inflated size
//! ([`MAX_INFLATED_BYTES`]) and on the number of values ([`MAX_VALUES`]), and
//! a truncated or corrupt file, a MAT v7.3 (HDF5) file and a MAT v4 file each
//! get their own error. Cell, struct, object, char and sparse arrays are
//! skipped (a signal is a numeric array).

use std::io::Read;
use thiserror::Error;

/// Largest total size of the inflated compressed elements of one file.
pub const MAX_INFLATED_BYTES: usize = 256 << 20;
/// Largest number of values (elements) of all arrays of one file.
pub const MAX_VALUES: usize = 32 << 20;

/// Why a MAT file cannot be read.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MatError {
    #[error("truncated or corrupt MAT file: {0}")]
    Corrupt(String),
    #[error("a MAT v7.3 (HDF5) file, which is not supported: save it in MATLAB with save(FILE, ..., '-v7') or export the signal as CSV")]
    V73,
    #[error("a MAT v4 file, which is not supported: save it in MATLAB with save(FILE, ..., '-v7') or export the signal as CSV")]
    V4,
    #[error("not a MAT file (no 'MATLAB 5.0 MAT-file' header); save it in MATLAB with save(FILE, ..., '-v7') or give a CSV file")]
    NotMat,
    #[error("too large: {0}")]
    TooLarge(String),
}

/// One real or complex numeric array.
#[derive(Debug, Clone, PartialEq)]
pub struct MatArray {
    pub name: String,
    /// Dimensions (MATLAB order, column-major data).
    pub dims: Vec<usize>,
    /// Real part, `dims.product()` values.
    pub real: Vec<f64>,
    /// The array has an imaginary part (not kept).
    pub complex: bool,
}

impl MatArray {
    pub fn numel(&self) -> usize {
        self.real.len()
    }
}

#[derive(Clone, Copy)]
struct Reader<'a> {
    big_endian: bool,
    bytes: &'a [u8],
}

/// Budget shared by all elements of a file.
struct Budget {
    inflated: usize,
    values: usize,
}

const MI_INT8: u32 = 1;
const MI_UINT32: u32 = 6;
const MI_INT32: u32 = 5;
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;

fn corrupt(msg: String) -> MatError {
    MatError::Corrupt(msg)
}

impl Reader<'_> {
    fn u32_at(&self, off: usize) -> Option<u32> {
        let b: [u8; 4] = self.bytes.get(off..off.checked_add(4)?)?.try_into().ok()?;
        Some(if self.big_endian {
            u32::from_be_bytes(b)
        } else {
            u32::from_le_bytes(b)
        })
    }
}

/// A data element: type, payload and the offset just after it.
struct Element<'a> {
    ty: u32,
    data: &'a [u8],
    next: usize,
}

/// Reads the element tag at `off` of `r` (`base` is the offset of `r` in
/// the file, for messages).
fn element<'a>(r: Reader<'a>, off: usize, base: usize) -> Result<Element<'a>, MatError> {
    let at = base + off;
    let remain = r.bytes.len().saturating_sub(off);
    let first = r.u32_at(off).ok_or_else(|| {
        corrupt(format!(
            "data element at byte {at} is cut off ({remain} bytes left, a tag needs 8)"
        ))
    })?;
    if first >> 16 != 0 {
        // small data element: 2-byte size, 2-byte type, 4 bytes of data
        let (ty, n) = (first & 0xffff, (first >> 16) as usize);
        if n > 4 {
            return Err(corrupt(format!(
                "small data element at byte {at} claims {n} bytes (at most 4)"
            )));
        }
        let data = r
            .bytes
            .get(off + 4..off + 4 + n)
            .ok_or_else(|| corrupt(format!("data element at byte {at} is cut off")))?;
        return Ok(Element {
            ty,
            data,
            next: off + 8,
        });
    }
    let n = r.u32_at(off + 4).ok_or_else(|| {
        corrupt(format!(
            "data element at byte {at} is cut off ({remain} bytes left, a tag needs 8)"
        ))
    })? as usize;
    let start = off + 8;
    let end = start
        .checked_add(n)
        .filter(|&e| e <= r.bytes.len())
        .ok_or_else(|| {
            corrupt(format!(
                "data element at byte {at} claims {n} bytes but only {} remain",
                r.bytes.len().saturating_sub(start)
            ))
        })?;
    // Uncompressed elements are padded to 8 bytes (the last one of a file
    // may lack its padding); compressed ones are not.
    let next = if first == MI_COMPRESSED {
        end
    } else {
        end.checked_add(7)
            .map(|e| e / 8 * 8)
            .unwrap_or(end)
            .min(r.bytes.len())
            .max(end)
    };
    Ok(Element {
        ty: first,
        data: &r.bytes[start..end],
        next,
    })
}

/// Bytes per value of a numeric data type, or `None`.
fn type_size(ty: u32) -> Option<usize> {
    match ty {
        1 | 2 => Some(1),
        3 | 4 => Some(2),
        5 | 6 | 7 => Some(4),
        9 | 12 | 13 => Some(8),
        _ => None,
    }
}

fn convert(ty: u32, data: &[u8], big_endian: bool) -> Vec<f64> {
    macro_rules! conv {
        ($t:ty) => {{
            const N: usize = std::mem::size_of::<$t>();
            data.chunks_exact(N)
                .map(|c| {
                    let b: [u8; N] = c.try_into().unwrap_or([0; N]);
                    (if big_endian {
                        <$t>::from_be_bytes(b)
                    } else {
                        <$t>::from_le_bytes(b)
                    }) as f64
                })
                .collect()
        }};
    }
    match ty {
        1 => conv!(i8),
        2 => conv!(u8),
        3 => conv!(i16),
        4 => conv!(u16),
        5 => conv!(i32),
        6 => conv!(u32),
        7 => conv!(f32),
        9 => conv!(f64),
        12 => conv!(i64),
        13 => conv!(u64),
        _ => Vec::new(),
    }
}

/// Parses the sub-elements of a miMATRIX element; `None` for a
/// non-numeric array (skipped).
fn matrix(r: Reader<'_>, base: usize, budget: &mut Budget) -> Result<Option<MatArray>, MatError> {
    if r.bytes.is_empty() {
        return Ok(None); // an empty miMATRIX is an empty array
    }
    let sub = |off| element(r, off, base);
    let flags = sub(0)?;
    if flags.ty != MI_UINT32 || flags.data.len() < 8 {
        return Err(corrupt(format!(
            "array at byte {base}: array flags missing"
        )));
    }
    let fr = Reader {
        big_endian: r.big_endian,
        bytes: flags.data,
    };
    let w0 = fr.u32_at(0).unwrap_or(0);
    let class = w0 & 0xff;
    let complex = w0 & 0x0800 != 0;
    if !(6..=15).contains(&class) {
        return Ok(None);
    }
    let dims_el = sub(flags.next)?;
    if dims_el.ty != MI_INT32 || dims_el.data.len() % 4 != 0 || dims_el.data.len() < 8 {
        return Err(corrupt(format!("array at byte {base}: dimensions missing")));
    }
    let dr = Reader {
        big_endian: r.big_endian,
        bytes: dims_el.data,
    };
    let mut dims = Vec::with_capacity(dims_el.data.len() / 4);
    let mut numel: usize = 1;
    for k in 0..dims_el.data.len() / 4 {
        let d = dr.u32_at(4 * k).unwrap_or(0) as i32;
        if d < 0 {
            return Err(corrupt(format!("array at byte {base}: dimension {d} < 0")));
        }
        dims.push(d as usize);
        numel = numel.checked_mul(d as usize).unwrap_or(usize::MAX);
    }
    if numel > MAX_VALUES || budget.values.saturating_add(numel) > MAX_VALUES {
        return Err(MatError::TooLarge(format!(
            "array at byte {base} has dimensions {dims:?}; a file may hold at most {MAX_VALUES} values"
        )));
    }
    let name_el = sub(dims_el.next)?;
    if name_el.ty != MI_INT8 && name_el.ty != 2 {
        return Err(corrupt(format!("array at byte {base}: name missing")));
    }
    let name = String::from_utf8_lossy(name_el.data).into_owned();
    let re = sub(name_el.next)?;
    let size = type_size(re.ty).ok_or_else(|| {
        corrupt(format!(
            "array {name:?}: data type {} is not numeric",
            re.ty
        ))
    })?;
    if re.data.len() != numel * size {
        return Err(corrupt(format!(
            "array {name:?} has dimensions {dims:?} ({numel} values) but {} bytes of data of {size} byte(s) each",
            re.data.len()
        )));
    }
    if complex {
        let im = sub(re.next)?;
        if type_size(im.ty)
            .map(|s| im.data.len() != numel * s)
            .unwrap_or(true)
        {
            return Err(corrupt(format!(
                "array {name:?}: imaginary part does not match its dimensions"
            )));
        }
    }
    budget.values += numel;
    Ok(Some(MatArray {
        name,
        dims,
        real: convert(re.ty, re.data, r.big_endian),
        complex,
    }))
}

fn inflate(data: &[u8], at: usize, budget: &mut Budget) -> Result<Vec<u8>, MatError> {
    let left = MAX_INFLATED_BYTES.saturating_sub(budget.inflated);
    let mut out = Vec::new();
    let mut dec = flate2::read::ZlibDecoder::new(data).take(left as u64 + 1);
    dec.read_to_end(&mut out).map_err(|e| {
        corrupt(format!(
            "compressed element at byte {at} does not inflate: {e}"
        ))
    })?;
    if out.len() > left {
        return Err(MatError::TooLarge(format!(
            "compressed data inflates to more than {MAX_INFLATED_BYTES} bytes"
        )));
    }
    budget.inflated += out.len();
    Ok(out)
}

/// Parses the top-level elements of `r`.
fn elements(
    r: Reader<'_>,
    base: usize,
    budget: &mut Budget,
    depth: usize,
    out: &mut Vec<MatArray>,
) -> Result<(), MatError> {
    let mut off = 0;
    while off < r.bytes.len() {
        let e = element(r, off, base)?;
        let at = base + off;
        match e.ty {
            MI_MATRIX => {
                let sub = Reader {
                    big_endian: r.big_endian,
                    bytes: e.data,
                };
                if let Some(a) = matrix(sub, at + 8, budget)? {
                    out.push(a);
                }
            }
            MI_COMPRESSED => {
                if depth > 0 {
                    return Err(corrupt(format!(
                        "compressed element at byte {at} inside a compressed element"
                    )));
                }
                let inner = inflate(e.data, at, budget)?;
                let sub = Reader {
                    big_endian: r.big_endian,
                    bytes: &inner,
                };
                elements(sub, at + 8, budget, depth + 1, out)?;
            }
            _ => {} // other top-level elements carry no array
        }
        off = e.next;
    }
    Ok(())
}

/// What the first bytes of a non-v5 file look like.
fn diagnose(bytes: &[u8]) -> MatError {
    if bytes.starts_with(b"MATLAB 7.3") || bytes.get(512..520) == Some(b"\x89HDF\r\n\x1a\n") {
        return MatError::V73;
    }
    if bytes.starts_with(b"\x89HDF\r\n\x1a\n") {
        return MatError::V73;
    }
    // MAT v4: 20-byte header of 5 int32 (type MOPT, rows, cols, imagf, namlen)
    for big in [false, true] {
        let r = Reader {
            big_endian: big,
            bytes,
        };
        let v: Vec<u32> = (0..5).filter_map(|k| r.u32_at(4 * k)).collect();
        if v.len() == 5 {
            let (mopt, rows, cols, imagf, namlen) = (v[0], v[1], v[2], v[3], v[4]);
            let (m, o, p, t) = (mopt / 1000, mopt / 100 % 10, mopt / 10 % 10, mopt % 10);
            if mopt < 5000
                && m <= 4
                && o == 0
                && p <= 5
                && t <= 2
                && rows < 1 << 28
                && cols < 1 << 28
                && imagf <= 1
                && (1..=64).contains(&namlen)
            {
                return MatError::V4;
            }
        }
    }
    MatError::NotMat
}

/// The numeric arrays of a MAT v5 file held in `bytes`.
pub fn parse(bytes: &[u8]) -> Result<Vec<MatArray>, MatError> {
    if bytes.is_empty() {
        return Err(corrupt("the file is empty".into()));
    }
    if bytes.len() < 128 || !bytes.starts_with(b"MATLAB") {
        if bytes.starts_with(b"MATLAB 5.0") {
            return Err(corrupt(format!(
                "{} bytes, shorter than the 128-byte header",
                bytes.len()
            )));
        }
        return Err(diagnose(bytes));
    }
    if bytes.starts_with(b"MATLAB 7.3") {
        return Err(MatError::V73);
    }
    let big_endian = match &bytes[126..128] {
        b"IM" => false,
        b"MI" => true,
        other => {
            return Err(corrupt(format!(
                "endian indicator {:?} is neither 'IM' nor 'MI'",
                String::from_utf8_lossy(other)
            )))
        }
    };
    let mut budget = Budget {
        inflated: 0,
        values: 0,
    };
    let mut out = Vec::new();
    let r = Reader {
        big_endian,
        bytes: &bytes[128..],
    };
    elements(r, 128, &mut budget, 0, &mut out)?;
    Ok(out)
}

/// Reads and parses a MAT file; refuses files larger than
/// [`MAX_INFLATED_BYTES`].
pub fn read(path: &std::path::Path) -> Result<Result<Vec<MatArray>, MatError>, std::io::Error> {
    let len = std::fs::metadata(path)?.len();
    if len > MAX_INFLATED_BYTES as u64 {
        return Ok(Err(MatError::TooLarge(format!(
            "the file has {len} bytes; at most {MAX_INFLATED_BYTES} are read"
        ))));
    }
    let bytes = std::fs::read(path)?;
    Ok(parse(&bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header() -> Vec<u8> {
        let mut out = vec![b' '; 116];
        out[..20].copy_from_slice(b"MATLAB 5.0 MAT-file,");
        out.extend([0u8; 8]);
        out.extend(0x0100u16.to_le_bytes());
        out.extend(*b"IM");
        out
    }

    fn matrix_el(name: &str, data: &[f64]) -> Vec<u8> {
        let mut p = Vec::new();
        for v in [6u32, 8, 6, 0, 5, 8] {
            p.extend(v.to_le_bytes());
        }
        p.extend((data.len() as i32).to_le_bytes());
        p.extend(1i32.to_le_bytes());
        p.extend(1u32.to_le_bytes());
        p.extend((name.len() as u32).to_le_bytes());
        p.extend(name.as_bytes());
        while p.len() % 8 != 0 {
            p.push(0);
        }
        p.extend(9u32.to_le_bytes());
        p.extend(((8 * data.len()) as u32).to_le_bytes());
        for v in data {
            p.extend(v.to_le_bytes());
        }
        let mut out = Vec::new();
        out.extend(14u32.to_le_bytes());
        out.extend((p.len() as u32).to_le_bytes());
        out.extend(p);
        out
    }

    fn compressed(el: &[u8]) -> Vec<u8> {
        use std::io::Write;
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(el).unwrap();
        let c = z.finish().unwrap();
        let mut out = Vec::new();
        out.extend(15u32.to_le_bytes());
        out.extend((c.len() as u32).to_le_bytes());
        out.extend(c);
        out
    }

    #[test]
    fn plain_and_compressed_arrays() {
        let mut f = header();
        f.extend(matrix_el("x", &[1.0, 2.5, -3.0]));
        f.extend(compressed(&matrix_el("fs", &[100.0])));
        let a = parse(&f).unwrap();
        assert_eq!(a.len(), 2);
        assert_eq!(a[0].name, "x");
        assert_eq!(a[0].real, vec![1.0, 2.5, -3.0]);
        assert_eq!(a[1].name, "fs");
        assert_eq!(a[1].real, vec![100.0]);
    }

    #[test]
    fn truncated_file_says_so() {
        let mut f = header();
        f.extend(matrix_el("x", &[1.0; 100]));
        for cut in [130, 200, f.len() - 9] {
            let e = parse(&f[..cut]).unwrap_err();
            assert!(matches!(e, MatError::Corrupt(_)), "{cut}: {e}");
            assert!(e.to_string().contains("truncated or corrupt"), "{e}");
        }
    }

    #[test]
    fn v73_and_v4_are_named() {
        let mut h5 = vec![b' '; 512];
        h5[..19].copy_from_slice(b"MATLAB 7.3 MAT-file");
        h5.extend(b"\x89HDF\r\n\x1a\n");
        assert_eq!(parse(&h5).unwrap_err(), MatError::V73);
        let mut v4 = Vec::new();
        for v in [0u32, 3, 1, 0, 2] {
            v4.extend(v.to_le_bytes());
        }
        v4.extend(b"x\0");
        for v in [1.0f64, 2.0, 3.0] {
            v4.extend(v.to_le_bytes());
        }
        assert_eq!(parse(&v4).unwrap_err(), MatError::V4);
        assert!(parse(&v4).unwrap_err().to_string().contains("-v7"));
        assert_eq!(parse(b"t,accel\n0,1\n").unwrap_err(), MatError::NotMat);
    }

    #[test]
    fn inflation_is_bounded() {
        // 300 MB of zeros inside one compressed element: refused without
        // holding more than the limit (256 MiB).
        use std::io::Write;
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
        let zeros = vec![0u8; 1 << 20];
        for _ in 0..300 {
            z.write_all(&zeros).unwrap();
        }
        let c = z.finish().unwrap();
        let mut f = header();
        f.extend(15u32.to_le_bytes());
        f.extend((c.len() as u32).to_le_bytes());
        f.extend(c);
        let e = parse(&f).unwrap_err();
        assert!(matches!(e, MatError::TooLarge(_)), "{e}");
    }

    #[test]
    fn huge_dimensions_are_refused() {
        let mut f = header();
        let mut el = matrix_el("x", &[1.0]);
        // dimensions 1x1 -> 100000 x 100000
        el[8 + 16 + 8..8 + 16 + 12].copy_from_slice(&100_000i32.to_le_bytes());
        el[8 + 16 + 12..8 + 16 + 16].copy_from_slice(&100_000i32.to_le_bytes());
        f.extend(el);
        assert!(matches!(parse(&f).unwrap_err(), MatError::TooLarge(_)));
    }
}
