//! The report's tables (markdown and CSV from one value) and its number
//! format.

use std::fmt::Write as _;

/// `v` with `n` significant digits, plain notation for 1e-3 <= |v| < 1e6.
pub fn sig(v: f64, n: usize) -> String {
    if !v.is_finite() {
        return if v.is_nan() {
            "-".into()
        } else {
            format!("{v}")
        };
    }
    if v == 0.0 {
        return "0".into();
    }
    let e = v.abs().log10().floor() as i32;
    if (-3..6).contains(&e) {
        let d = (n as i32 - 1 - e).max(0) as usize;
        format!("{v:.d$}")
    } else {
        format!("{:.*e}", n.saturating_sub(1), v)
    }
}

/// A table rendered both as markdown and CSV.
pub struct Table {
    pub name: &'static str,
    pub headers: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

impl Table {
    pub fn new(name: &'static str, headers: &[&str]) -> Self {
        Self {
            name,
            headers: headers.iter().map(|s| s.to_string()).collect(),
            rows: Vec::new(),
        }
    }
    pub fn push(&mut self, row: Vec<String>) {
        self.rows.push(row);
    }
    pub fn markdown(&self) -> String {
        let esc = |c: &String| c.replace('|', "\\|");
        let mut s = String::new();
        let _ = writeln!(
            s,
            "| {} |",
            self.headers.iter().map(esc).collect::<Vec<_>>().join(" | ")
        );
        let _ = writeln!(
            s,
            "|{}",
            self.headers.iter().map(|_| " --- |").collect::<String>()
        );
        for r in &self.rows {
            let _ = writeln!(
                s,
                "| {} |",
                r.iter()
                    .map(esc)
                    .collect::<Vec<_>>()
                    .join(" | ")
                    .replace('\n', " ")
            );
        }
        s
    }
    pub fn csv(&self) -> String {
        let q = |c: &str| {
            let c = c.replace("<br>", " ");
            if c.contains(',') || c.contains('"') {
                format!("\"{}\"", c.replace('"', "\"\""))
            } else {
                c
            }
        };
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{}",
            self.headers
                .iter()
                .map(|h| q(h))
                .collect::<Vec<_>>()
                .join(",")
        );
        for r in &self.rows {
            let _ = writeln!(
                s,
                "{}",
                r.iter().map(|c| q(c)).collect::<Vec<_>>().join(",")
            );
        }
        s
    }
}
