//! Deserialising the `&'static str` names the identification results carry
//! (parameter names, stage names): each distinct name is leaked once and
//! reused, so a result read back (Python's pickling of a fit) holds the
//! same kind of names as one computed, with memory bounded by the set of
//! names. Serialisation is serde's for `&str`.

use serde::{Deserialize, Deserializer};

/// A name field of a serialisable result. Spelled through this alias so that
/// serde's derive does not take the field as borrowed from the input (it
/// does so for a literal `&str` type, which would tie the result to the
/// buffer it was read from); read back by [`name`].
pub type Name = &'static str;
use std::collections::HashSet;
use std::sync::{Mutex, OnceLock};

/// The one `&'static str` with this text.
pub fn intern(s: &str) -> &'static str {
    static SET: OnceLock<Mutex<HashSet<&'static str>>> = OnceLock::new();
    let mut set = SET
        .get_or_init(|| Mutex::new(HashSet::new()))
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    if let Some(&known) = set.get(s) {
        return known;
    }
    let leaked: &'static str = Box::leak(s.to_owned().into_boxed_str());
    set.insert(leaked);
    leaked
}

/// `#[serde(deserialize_with = "crate::interned::name")]`
pub fn name<'de, D: Deserializer<'de>>(d: D) -> Result<&'static str, D::Error> {
    Ok(intern(&String::deserialize(d)?))
}

/// `#[serde(deserialize_with = "crate::interned::names")]`
pub fn names<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<&'static str>, D::Error> {
    Ok(Vec::<String>::deserialize(d)?
        .iter()
        .map(|s| intern(s))
        .collect())
}

/// `#[serde(deserialize_with = "crate::interned::optional_name")]`
pub fn optional_name<'de, D: Deserializer<'de>>(d: D) -> Result<Option<&'static str>, D::Error> {
    Ok(Option::<String>::deserialize(d)?.map(|s| intern(&s)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_name_is_leaked_once() {
        let a = intern("kappa");
        let b = intern(&String::from("kappa"));
        assert!(std::ptr::eq(a, b));
        assert_eq!(a, "kappa");
    }
}
