//! The profile file's layout (TOML, serde, unknown keys refused): a `[profile]` table and
//! `[[element]]` tables, parsed as written. Nothing here checks ranges:
//! [`lower`](mod@super::lower) does, against a device.
//!
//! Units: fixed by `[profile] axis`: `linear` m, N/m, N·s/m, N; `rotary` rad, N·m/rad,
//! N·m·s/rad, N·m. Positions (`at`, `min`, `max`, `center`, `first`, `from`, `to`) and the
//! detents' `pitch` are in m (rad), or in raw encoder counts with `positions = "counts"`.
//! The format, key by key: `profiles/README.md`.

use super::error::{Place, ProfileError};
use serde::Deserialize;

/// The axis of the profile, which fixes its units.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    /// m, N/m, N·s/m, N.
    Linear,
    /// rad, N·m/rad, N·m·s/rad, N·m.
    Rotary,
}

/// How the file writes positions and the detents' pitch.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Positions {
    /// m (rad): rounded to the nearest count boundary for the device.
    #[default]
    Si,
    /// Raw encoder counts (whole numbers; a pitch may be fractional).
    Counts,
}

/// The `[profile]` table.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Header {
    /// The profile's name.
    pub name: String,
    /// Linear or rotary.
    pub axis: Axis,
    /// SI positions (default) or raw counts.
    #[serde(default)]
    pub positions: Positions,
    /// The devices (preset names) or plant files (paths ending in `.toml`) the profile was
    /// checked for.
    #[serde(default)]
    pub checked_for: Vec<String>,
}

/// A wall side as written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SideSpec {
    /// Occupies positions at or above `at`, pushes down.
    Upper,
    /// Occupies positions below `at`, pushes up.
    Lower,
}

fn dead_band_1() -> String {
    "dead-band-1".to_owned()
}

/// `kind = "wall"`: a one-sided wall.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallSpec {
    /// The wall's surface.
    pub at: f64,
    /// Which side of `at` it occupies.
    pub side: SideSpec,
    /// K.
    pub stiffness: f64,
    /// B (default 0).
    #[serde(default)]
    pub damping: f64,
    /// The damper's law (default `dead-band-1`).
    #[serde(default = "dead_band_1")]
    pub damper: String,
}

/// `kind = "end-stops"`: a lower wall at `min` and an upper wall at `max`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EndStopsSpec {
    /// The lower wall's surface (it occupies positions below).
    pub min: f64,
    /// The upper wall's surface (it occupies positions at or above).
    pub max: f64,
    /// K of both.
    pub stiffness: f64,
    /// B of both (default 0).
    #[serde(default)]
    pub damping: f64,
    /// The damper's law (default `dead-band-1`).
    #[serde(default = "dead_band_1")]
    pub damper: String,
}

/// `kind = "detents"`: a train of sinusoidal detents.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DetentsSpec {
    /// The first minimum.
    pub first: f64,
    /// How many minima.
    pub count: u32,
    /// Minimum to minimum (exactly one of `pitch` and `per_rev`).
    #[serde(default)]
    pub pitch: Option<f64>,
    /// Detents per revolution, rotary only (exactly one of `pitch` and `per_rev`).
    #[serde(default)]
    pub per_rev: Option<f64>,
    /// Peak force A.
    pub strength: f64,
    /// B inside the train (default 0).
    #[serde(default)]
    pub damping: f64,
    /// The damper's law (default `dead-band-1`).
    #[serde(default = "dead_band_1")]
    pub damper: String,
}

/// `kind = "spring"`: a two-sided centring spring.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpringSpec {
    /// The spring's origin.
    pub center: f64,
    /// K.
    pub stiffness: f64,
    /// B (default 0).
    #[serde(default)]
    pub damping: f64,
    /// The damper's law (default `dead-band-1`).
    #[serde(default = "dead_band_1")]
    pub damper: String,
}

/// `kind = "viscous"`: a viscous zone `[from, to)`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViscousSpec {
    /// First position inside.
    pub from: f64,
    /// First position past the zone.
    pub to: f64,
    /// B.
    pub damping: f64,
    /// The damper's law (default `dead-band-1`).
    #[serde(default = "dead_band_1")]
    pub damper: String,
}

/// One `[[element]]` table, by its `kind`.
#[derive(Debug, Clone, PartialEq)]
pub enum ElementSpec {
    /// `wall`.
    Wall(WallSpec),
    /// `end-stops`.
    EndStops(EndStopsSpec),
    /// `detents`.
    Detents(DetentsSpec),
    /// `spring`.
    Spring(SpringSpec),
    /// `viscous`.
    Viscous(ViscousSpec),
}

/// The kinds, as `kind` spells them.
pub const KINDS: [&str; 5] = ["wall", "end-stops", "detents", "spring", "viscous"];

impl ElementSpec {
    /// Its `kind`.
    #[must_use]
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Wall(_) => KINDS[0],
            Self::EndStops(_) => KINDS[1],
            Self::Detents(_) => KINDS[2],
            Self::Spring(_) => KINDS[3],
            Self::Viscous(_) => KINDS[4],
        }
    }
}

/// A profile file as written.
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileFile {
    /// `[profile]`.
    pub header: Header,
    /// The `[[element]]` tables in file order.
    pub elements: Vec<ElementSpec>,
}

impl ProfileFile {
    /// Parses a profile file's text.
    ///
    /// # Errors
    /// [`ProfileError::Syntax`] naming the table (an element by number and kind) for bad TOML,
    /// an unknown table, key or kind, a missing key or a value of the wrong type.
    pub fn from_toml(text: &str) -> Result<Self, ProfileError> {
        let syntax = |place: Place, e: &dyn std::fmt::Display| ProfileError::Syntax {
            place,
            message: e.to_string().trim_end().to_owned(),
        };
        let mut table: toml::Table = toml::from_str(text).map_err(|e| syntax(Place::File, &e))?;
        if let Some(key) = table.keys().find(|k| *k != "profile" && *k != "element") {
            return Err(syntax(
                Place::File,
                &format!(
                    "unknown key `{key}`: a profile file has `[profile]` and `[[element]]` tables"
                ),
            ));
        }
        let header = table
            .remove("profile")
            .ok_or_else(|| syntax(Place::File, &"missing the `[profile]` table"))?;
        let header: Header = header.try_into().map_err(|e| syntax(Place::Header, &e))?;
        let elements = match table.remove("element") {
            None => Vec::new(),
            Some(toml::Value::Array(items)) => items
                .into_iter()
                .enumerate()
                .map(|(i, v)| element(i + 1, v))
                .collect::<Result<_, _>>()?,
            Some(_) => {
                return Err(syntax(
                    Place::File,
                    &"`element` must be an array of tables (`[[element]]`)",
                ))
            }
        };
        Ok(Self { header, elements })
    }
}

/// The `index`-th element table: its `kind`, then that kind's keys.
fn element(index: usize, value: toml::Value) -> Result<ElementSpec, ProfileError> {
    let err = |kind: &str, message: String| ProfileError::Syntax {
        place: Place::Element {
            index,
            kind: kind.to_owned(),
        },
        message,
    };
    let toml::Value::Table(mut t) = value else {
        return Err(err(
            "?",
            "an element must be a table (`[[element]]`)".into(),
        ));
    };
    let allowed = KINDS.map(|k| format!("`{k}`")).join(", ");
    let kind = match t.remove("kind") {
        Some(toml::Value::String(k)) => k,
        Some(v) => {
            return Err(err(
                "?",
                format!("`kind` must be one of {allowed} (got {v})"),
            ))
        }
        None => return Err(err("?", format!("missing `kind` (one of {allowed})"))),
    };
    let body = toml::Value::Table(t);
    let parsed = match kind.as_str() {
        "wall" => body.try_into().map(ElementSpec::Wall),
        "end-stops" => body.try_into().map(ElementSpec::EndStops),
        "detents" => body.try_into().map(ElementSpec::Detents),
        "spring" => body.try_into().map(ElementSpec::Spring),
        "viscous" => body.try_into().map(ElementSpec::Viscous),
        _ => {
            return Err(err(
                "?",
                format!("unknown kind `{kind}` (allowed: {allowed})"),
            ))
        }
    };
    parsed.map_err(|e| err(&kind, e.to_string().trim_end().to_owned()))
}

#[cfg(test)]
mod tests {
    use super::*;

    const WALL: &str = "[profile]\nname = \"w\"\naxis = \"linear\"\n\n[[element]]\n\
                        kind = \"wall\"\nat = 0.01\nside = \"upper\"\nstiffness = 500\n";

    #[test]
    fn a_wall_with_its_defaults() {
        let f = ProfileFile::from_toml(WALL).unwrap();
        assert_eq!(f.header.axis, Axis::Linear);
        assert_eq!(f.header.positions, Positions::Si);
        assert!(f.header.checked_for.is_empty());
        let ElementSpec::Wall(w) = &f.elements[0] else {
            panic!("{f:?}")
        };
        assert_eq!((w.at, w.side, w.stiffness), (0.01, SideSpec::Upper, 500.0));
        assert_eq!((w.damping, w.damper.as_str()), (0.0, "dead-band-1"));
    }

    #[test]
    fn unknown_keys_and_kinds_name_the_element() {
        let e = ProfileFile::from_toml(&format!("{WALL}stifness = 3\n")).unwrap_err();
        let m = e.to_string();
        assert!(
            m.starts_with("element 1 (wall): unknown field `stifness`"),
            "{m}"
        );
        let e = ProfileFile::from_toml(&WALL.replace("\"wall\"", "\"wal\"")).unwrap_err();
        assert!(
            e.to_string().contains("element 1 (?): unknown kind `wal`"),
            "{e}"
        );
        let e = ProfileFile::from_toml(&format!("{WALL}[extra]\n")).unwrap_err();
        assert!(e.to_string().contains("unknown key `extra`"), "{e}");
        let e = ProfileFile::from_toml(&WALL.replace("axis", "units = 1\naxis")).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("[profile]: unknown field `units`"),
            "{e}"
        );
        let e = ProfileFile::from_toml(&WALL.replace("\"linear\"", "\"planar\"")).unwrap_err();
        assert!(e.to_string().contains("linear"), "{e}");
    }

    #[test]
    fn nan_and_inf_parse_for_the_lowering_to_refuse() {
        let f = ProfileFile::from_toml(&WALL.replace("500", "nan")).unwrap();
        let ElementSpec::Wall(w) = &f.elements[0] else {
            panic!()
        };
        assert!(w.stiffness.is_nan());
    }
}
