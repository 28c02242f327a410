//! What is wrong with a profile file: [`ProfileError`], each variant naming where (the
//! `[profile]` table or an element by its number and kind), the key, the allowed range and
//! the value given. Nothing is produced from a file with an error.
//!
//! Invariant: every message names a place a user can find in the file: elements are numbered
//! from 1 in file order (the n-th `[[element]]` table), as the check's report numbers them.

use std::fmt;

/// Where in a profile file an error is: the `[profile]` table, an element, or the file as a
/// whole.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Place {
    /// The file as a whole (TOML syntax, a table the format does not have).
    File,
    /// The `[profile]` table.
    Header,
    /// The `index`-th `[[element]]` table (from 1) of kind `kind` (`?` when its `kind` is
    /// missing or unknown).
    Element {
        /// Its number in file order, from 1.
        index: usize,
        /// Its `kind` as written, or `?`.
        kind: String,
    },
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::File => f.write_str("profile file"),
            Self::Header => f.write_str("[profile]"),
            Self::Element { index, kind } => write!(f, "element {index} ({kind})"),
        }
    }
}

/// A profile file refused: nothing was produced.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ProfileError {
    /// Not TOML, a key or table the format does not have, a missing key or a value of the
    /// wrong type (serde's message, which names the key and the keys allowed).
    #[error("{place}: {message}")]
    Syntax {
        /// Where.
        place: Place,
        /// What serde or the TOML parser said.
        message: String,
    },
    /// A key's value outside its allowed range.
    #[error("{place}: `{field}` must be {allowed} (got {got})")]
    Field {
        /// Where.
        place: Place,
        /// The key, as the file spells it.
        field: &'static str,
        /// The allowed range in words, with units.
        allowed: String,
        /// The value given, as written back.
        got: String,
    },
    /// More wire elements than the servo's table holds (an `end-stops` element is two walls).
    #[error(
        "the profile lowers to {count} elements (an `end-stops` element is two walls); the \
         device renders at most {max}"
    )]
    TooMany {
        /// Wire elements after lowering.
        count: usize,
        /// The most the servo renders ([`stiffwall_proto::MAX_PROFILE_ELEMENTS`]).
        max: usize,
    },
    /// Two elements that overlap in a way that makes no sense.
    #[error("{first} and {second}: {why}")]
    Overlap {
        /// The earlier element.
        first: Place,
        /// The later element.
        second: Place,
        /// What is wrong, with the counts.
        why: String,
    },
}

/// A number as an error message writes it back: plain when short, else in exponent form
/// (`1e300`, not 301 digits).
#[must_use]
pub fn got(x: f64) -> String {
    let (plain, sci) = (format!("{x}"), format!("{x:e}"));
    if sci.len() < plain.len() {
        sci
    } else {
        plain
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn places_and_values_read_as_written() {
        let p = Place::Element {
            index: 3,
            kind: "detents".into(),
        };
        assert_eq!(p.to_string(), "element 3 (detents)");
        assert_eq!(got(1e300), "1e300");
        assert_eq!(got(0.25), "0.25");
        assert_eq!(got(f64::NAN), "NaN");
        let e = ProfileError::Field {
            place: p,
            field: "stiffness",
            allowed: "finite".into(),
            got: got(f64::INFINITY),
        };
        assert_eq!(
            e.to_string(),
            "element 3 (detents): `stiffness` must be finite (got inf)"
        );
    }
}
