//! Universal-file functions ([`crate::uff58`]) as the project's data: the
//! rules shared by the FRF reader ([`crate::frf_file::read_frf`]), the
//! time-history channels of `frf-estimate`
//! ([`crate::frf_file::read_channel`]) and the stepped-sine FRF sets of
//! `fit` ([`crate::stepped_sine_data::read_uff`]).
//!
//! * **Choosing a dataset** ([`select`]): a number is the dataset's index
//!   among the file's dataset-58 functions (from 0, as
//!   [`crate::signal_file::read_uff`] and pyuff count them; from 1 where a
//!   verb numbers its channels from 1), any other text is looked for in ID
//!   line 1 (case-sensitive) and must match exactly one dataset. Without a
//!   selector the verb's default applies; an ambiguous or empty choice is
//!   refused with the list of the file's datasets.
//! * **Abscissa**: a frequency is an axis with units label `Hz`, or
//!   specific data type 18 (frequency) and no units label; a time an axis
//!   with units label `s`, or specific data type 17 (time) and no units
//!   label. Anything else is refused naming what the axis is.
//! * **Response quantities** ([`quantity`]): from the axis's specific data
//!   type (8 displacement, 11 velocity, 12 acceleration, 13 force) or its
//!   SI units label (`m`, `m/s`, `m/s^2`, `N`); a label in other units
//!   (`g`, `mm`, `in/s`) or contradicting the data type is refused (units
//!   are not converted), as are unit exponents other than length 0 or 1
//!   and force 0 for a motion.
//! * **ID-line tokens** ([`id_token`]): `key=value` words (separated by
//!   blanks, commas or semicolons) in ID lines 1–5, e.g. `gamma=2.5
//!   sweep=down level=L3`.

use crate::uff58::{
    function_type_name, specific_data_type_name, AxisInfo, Uff58Function, Uff58Header,
};
use std::path::Path;

/// Whether `path` names a universal file (extension `.uff` or `.unv`,
/// case-insensitive).
pub fn is_uff(path: &Path) -> bool {
    path.extension()
        .map(|e| e.eq_ignore_ascii_case("uff") || e.eq_ignore_ascii_case("unv"))
        .unwrap_or(false)
}

/// The file's datasets for a message: `N: function type 'ID line 1'; ...`
/// with `N` from `base` (0 or 1).
pub fn listing(all: &[Uff58Function], base: usize) -> String {
    all.iter()
        .map(|f| {
            format!(
                "{}: {}{} '{}'",
                f.info.index + base,
                function_type_name(f.dataset.header.function_type),
                if f.info.complex {
                    ", complex"
                } else {
                    ", real"
                },
                f.dataset.header.id1.trim()
            )
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// The dataset chosen by `selector` (see the module documentation; numbers
/// counted from `base`, 0 or 1), or, without one, the only dataset for
/// which `default` holds (`what` describes those in messages, e.g. "is a
/// frequency response function"). `option` names the selector option.
pub fn select<'a>(
    all: &'a [Uff58Function],
    selector: Option<&str>,
    base: usize,
    option: &str,
    what: &str,
    default: impl Fn(&Uff58Function) -> bool,
) -> Result<&'a Uff58Function, String> {
    if all.is_empty() {
        return Err("the universal file holds no dataset 58".into());
    }
    let chosen: Vec<&Uff58Function> = match selector {
        Some(sel) => match sel.trim().parse::<usize>() {
            Ok(i) => all.iter().filter(|f| f.info.index + base == i).collect(),
            Err(_) => all
                .iter()
                .filter(|f| f.dataset.header.id1.contains(sel))
                .collect(),
        },
        None => all.iter().filter(|f| default(f)).collect(),
    };
    match chosen.as_slice() {
        [f] => Ok(f),
        [] => Err(format!(
            "no dataset {} (datasets: {})",
            match selector {
                Some(s) => format!("matches '{s}'"),
                None => what.to_string(),
            },
            listing(all, base)
        )),
        _ => Err(format!(
            "{} datasets {}; choose one by {} or ID-line-1 text with {option} (datasets: {})",
            chosen.len(),
            match selector {
                Some(s) => format!("match '{s}'"),
                None => format!("qualify (each {what})"),
            },
            if base == 0 {
                "index (from 0)"
            } else {
                "number (from 1)"
            },
            listing(all, base)
        )),
    }
}

fn no_units(units: &str) -> bool {
    let u = units.trim();
    u.is_empty() || u.eq_ignore_ascii_case("none")
}

fn describe(axis: &AxisInfo) -> String {
    format!(
        "{} (specific data type {}, units '{}')",
        specific_data_type_name(axis.specific_data_type),
        axis.specific_data_type,
        axis.units.trim()
    )
}

/// Refuses an abscissa that is not a frequency in Hz (see the module
/// documentation); `label` names the dataset in the message.
pub fn check_frequency_axis(label: &str, header: &Uff58Header) -> Result<(), String> {
    let a = &header.abscissa_axis;
    if a.units.trim().eq_ignore_ascii_case("hz")
        || (a.specific_data_type == 18 && no_units(&a.units))
    {
        return Ok(());
    }
    Err(format!(
        "{label}: the abscissa is {}, not a frequency in Hz (specific data type 18 or units 'Hz')",
        describe(a)
    ))
}

/// Refuses an abscissa that is not a time in s (see the module
/// documentation).
pub fn check_time_axis(label: &str, header: &Uff58Header) -> Result<(), String> {
    let a = &header.abscissa_axis;
    if a.units.trim() == "s" || (a.specific_data_type == 17 && no_units(&a.units)) {
        return Ok(());
    }
    Err(format!(
        "{label}: the abscissa is {}, not a time in s (specific data type 17 or units 's')",
        describe(a)
    ))
}

/// A physical quantity of an ordinate axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// m (specific data type 8).
    Displacement,
    /// m/s (11).
    Velocity,
    /// m/s² (12).
    Acceleration,
    /// N (13).
    Force,
}

impl Quantity {
    /// Name for messages.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Displacement => "displacement (m)",
            Quantity::Velocity => "velocity (m/s)",
            Quantity::Acceleration => "acceleration (m/s^2)",
            Quantity::Force => "force (N)",
        }
    }
}

fn from_units(units: &str) -> Option<Quantity> {
    let u: String = units
        .trim()
        .chars()
        .filter(|c| !c.is_whitespace())
        .collect();
    match u.as_str() {
        "m" => Some(Quantity::Displacement),
        "m/s" => Some(Quantity::Velocity),
        "m/s^2" | "m/s2" | "m/s**2" | "m/s\u{b2}" | "m s^-2" => Some(Quantity::Acceleration),
        "N" => Some(Quantity::Force),
        _ => None,
    }
}

/// The quantity of an ordinate axis (see the module documentation):
/// `Ok(None)` when the axis states none (specific data type 0 or 1 and no
/// units label), an error for non-SI units, contradictions and exponents
/// that do not fit. `which` names the axis in messages.
pub fn quantity(which: &str, axis: &AxisInfo) -> Result<Option<Quantity>, String> {
    let by_type = match axis.specific_data_type {
        8 => Some(Quantity::Displacement),
        11 => Some(Quantity::Velocity),
        12 => Some(Quantity::Acceleration),
        9 | 13 => Some(Quantity::Force),
        _ => None,
    };
    let by_units = if no_units(&axis.units) {
        None
    } else {
        match from_units(&axis.units) {
            Some(q) => Some(q),
            None => {
                return Err(format!(
                    "{which}: units '{}' are not SI (m, m/s, m/s^2 or N): units are not converted",
                    axis.units.trim()
                ))
            }
        }
    };
    let q = match (by_type, by_units) {
        (Some(a), Some(b)) if a != b => {
            return Err(format!(
                "{which}: specific data type {} ({}) contradicts units '{}'",
                axis.specific_data_type,
                specific_data_type_name(axis.specific_data_type),
                axis.units.trim()
            ))
        }
        (Some(a), _) => a,
        (None, Some(b)) => b,
        (None, None) => return Ok(None),
    };
    let (len, force) = (axis.length_exponent, axis.force_exponent);
    let fits = match q {
        Quantity::Force => len == 0 && (force == 0 || force == 1),
        _ => (len == 0 || len == 1) && force == 0,
    };
    if !fits {
        return Err(format!(
            "{which}: unit exponents length {len}, force {force} do not fit {}",
            q.name()
        ));
    }
    Ok(Some(q))
}

/// The value of the first `key=value` token (key case-insensitive) of ID
/// lines 1–5, with the ID line number (1–5).
pub fn id_token(header: &Uff58Header, key: &str) -> Option<(usize, String)> {
    let lines = [
        &header.id1,
        &header.id2,
        &header.id3,
        &header.id4,
        &header.id5,
    ];
    for (k, line) in lines.iter().enumerate() {
        for word in line.split(|c: char| c.is_whitespace() || c == ',' || c == ';') {
            if let Some((k2, v)) = word.split_once('=') {
                if k2.eq_ignore_ascii_case(key) && !v.is_empty() {
                    return Some((k + 1, v.to_string()));
                }
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_and_quantities() {
        let h = Uff58Header {
            id2: "run 3, gamma=2.5; sweep=DOWN".into(),
            ..Uff58Header::default()
        };
        assert_eq!(id_token(&h, "gamma"), Some((2, "2.5".into())));
        assert_eq!(id_token(&h, "SWEEP"), Some((2, "DOWN".into())));
        assert_eq!(id_token(&h, "level"), None);
        let q = |t: i32, u: &str| quantity("ordinate", &AxisInfo::new(t, "x", u));
        assert_eq!(q(12, "NONE"), Ok(Some(Quantity::Acceleration)));
        assert_eq!(q(0, "m/s"), Ok(Some(Quantity::Velocity)));
        assert_eq!(q(1, "NONE"), Ok(None));
        assert!(q(12, "g").unwrap_err().contains("units 'g' are not SI"));
        assert!(q(8, "m/s").unwrap_err().contains("contradicts"));
    }

    #[test]
    fn axes() {
        let mut h = Uff58Header {
            abscissa_axis: AxisInfo::new(18, "Frequency", "Hz"),
            ..Uff58Header::default()
        };
        assert!(check_frequency_axis("d", &h).is_ok());
        assert!(check_time_axis("d", &h).unwrap_err().contains("frequency"));
        h.abscissa_axis = AxisInfo::new(17, "Time", "s");
        let e = check_frequency_axis("dataset 0", &h).unwrap_err();
        assert!(e.contains("dataset 0: the abscissa is time"), "{e}");
        h.abscissa_axis = AxisInfo::new(18, "Frequency", "rad/s");
        assert!(check_frequency_axis("d", &h).is_err());
    }
}
