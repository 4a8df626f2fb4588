//! Format detection of the reader layer (issue 28, item 2) never panics on
//! arbitrary bytes, whatever the file name, and never quotes raw bytes in
//! what it says about a file that is not text.

use nlsdof_io::input::{detect, not_text_format, Format};
use proptest::prelude::*;
use std::path::Path;

const NAMES: [&str; 6] = ["a.csv", "a.mat", "a.uff", "a.lvm", "a.txt", "noext"];

fn printable(s: &str) -> bool {
    !s.chars().any(|c| c.is_control())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 20_000, ..ProptestConfig::default() })]

    #[test]
    fn detection_never_panics_on_random_bytes(
        bytes in proptest::collection::vec(any::<u8>(), 0..6000),
        name in 0usize..NAMES.len(),
    ) {
        let p = Path::new(NAMES[name]);
        let f = detect(&bytes, p);
        if let Format::Other(what) = &f {
            prop_assert!(printable(what), "{what:?}");
        }
        if let Some(what) = not_text_format(&bytes, p) {
            prop_assert!(printable(&what), "{what:?}");
        }
    }

    /// Random bytes after each format's magic: still never a panic, and the
    /// magic decides.
    #[test]
    fn detection_of_magic_prefixes(
        tail in proptest::collection::vec(any::<u8>(), 0..3000),
        which in 0usize..4,
    ) {
        let magic: &[u8] = [
            &b"MATLAB 5.0 MAT-file, Platform: x"[..],
            b"    -1\n    58\n",
            b"LabVIEW Measurement\t\r\n",
            &[0x1f, 0x8b],
        ][which];
        let mut bytes = magic.to_vec();
        bytes.extend(&tail);
        let f = detect(&bytes, Path::new("x.dat"));
        match which {
            0 => prop_assert_eq!(f, Format::Mat),
            1 => prop_assert_eq!(f, Format::Uff),
            2 => prop_assert!(matches!(f, Format::Lvm | Format::Other(_))),
            _ => prop_assert!(matches!(f, Format::Other(ref w) if w.contains("gzip"))),
        }
    }
}

/// Every file read end to end through the reader layer: random content
/// under each name is an error or a table, never a panic.
#[test]
fn reading_random_files_never_panics() {
    let dir = tempfile::tempdir().unwrap();
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let seeds: [&[u8]; 5] = [
        b"t,x\n0,1\n0.1,2\n",
        b"LabVIEW Measurement\t\r\n***End_of_Header***\t\r\n***End_of_Header***\t\r\nX_Value\tx\r\n0\t1\r\n0.1\t2\r\n",
        b"Source File Name:\ta\n\nTime\tTime Signal\n[ s ]\t[ m/s ]\n0\t1\n0.1\t2\n",
        b"    -1\n    58\n",
        b"MATLAB 5.0 MAT-file",
    ];
    for i in 0..3000 {
        let seed = seeds[i % seeds.len()];
        let mut bytes = seed.to_vec();
        for _ in 0..(next() % 4) {
            let k = (next() as usize) % (bytes.len() + 1);
            match next() % 3 {
                0 => bytes.insert(k, next() as u8),
                1 if k < bytes.len() => {
                    bytes.remove(k);
                }
                _ => bytes.truncate(k),
            }
        }
        let p = dir.path().join(NAMES[i % NAMES.len()]);
        std::fs::write(&p, &bytes).unwrap();
        let _ = nlsdof_io::input::read_columns(&p, &["x"], true);
        if let Err(e) = nlsdof_io::input::read_signal(&p, Some("x"), None) {
            let m = e.to_string();
            assert!(!m.contains('\0'), "{m:?}");
        }
        let _ = nlsdof_io::frf_file::read_channel(&p, "1", None);
    }
}
