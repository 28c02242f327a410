//! Validation and lowering: a [`ProfileFile`] → the wire [`stiffwall_proto::Profile`] for a
//! [`Device`], every element checked (finite, in its field's range), positions in raw counts,
//! an `end-stops` element as two walls. The result ([`Lowered`]) keeps where each wire element came from, for
//! the check's report and its errors; [`Lowered::wire`] is the profile a device is sent.
//!
//! Units: SI positions are rounded to the nearest count boundary, round(x/Δ) (position 0 is
//! count 0, the count containing x is ⌊x/Δ⌋; a wall at x occupies the counts from that boundary
//! on, or below it); a detent pitch stays fractional, pitch/Δ counts, or (2π/Δ)/per_rev on a
//! rotary device. Stiffness and damping keep the device's units (N/m, N·s/m or N·m/rad,
//! N·m·s/rad), the detents' strength N (N·m).
//!
//! Invariants: [`lower`](fn@lower) returns a profile only when every field is in range, there are at most
//! [`MAX_PROFILE_ELEMENTS`] wire elements and no two elements overlap in a way that makes no
//! sense ([`super::overlap`]); otherwise the first error in file order, and nothing.

use super::error::{got, Place, ProfileError};
use super::file::{
    Axis, DetentsSpec, ElementSpec, EndStopsSpec, Positions, ProfileFile, SideSpec, ViscousSpec,
};
pub use super::placed::{Lowered, Origin, Placed};
use super::units::{sig, Device};
use stiffwall_proto::{DamperLaw, ProfileElement, Side, MAX_DETENTS, MAX_PROFILE_ELEMENTS};
use stiffwall_sim::scene::field_bounds::{DAMPING, STIFFNESS};

/// The smallest detent pitch, counts.
pub const MIN_PITCH_COUNTS: f64 = 2.0;

/// The largest detent strength A, N (N·m): the plausible force range of `field_bounds`'
/// Coulomb friction.
pub const MAX_STRENGTH: f64 = stiffwall_sim::scene::field_bounds::COULOMB.linear.1;

/// Checks `file` and lowers it for `device`.
///
/// # Errors
/// The first [`ProfileError`] in file order: a field out of range (named with its element and
/// allowed range), the axis not the device's, too many wire elements, an overlap that makes no
/// sense.
pub fn lower(file: &ProfileFile, device: &Device) -> Result<Lowered, ProfileError> {
    let wants_rotary = file.header.axis == Axis::Rotary;
    if wants_rotary != device.rotational {
        let (axis, other) = if device.rotational {
            ("rotary", "linear")
        } else {
            ("linear", "rotary")
        };
        return Err(ProfileError::Field {
            place: Place::Header,
            field: "axis",
            allowed: format!(
                "`{axis}` on this device (it is {axis}; Δ = {} {})",
                sig(device.resolution),
                device.units().position
            ),
            got: format!("`{other}`"),
        });
    }
    let mut elements = Vec::new();
    for (i, spec) in file.elements.iter().enumerate() {
        let origin = Origin {
            index: i + 1,
            kind: spec.kind(),
            part: None,
        };
        let cx = Cx {
            device,
            positions: file.header.positions,
            place: origin.place(),
        };
        cx.element(spec, origin, &mut elements)?;
    }
    if elements.len() > MAX_PROFILE_ELEMENTS {
        return Err(ProfileError::TooMany {
            count: elements.len(),
            max: MAX_PROFILE_ELEMENTS,
        });
    }
    super::overlap::refuse_nonsense(&elements)?;
    Ok(Lowered {
        name: file.header.name.clone(),
        device: *device,
        elements,
    })
}

/// Checks one element's fields for one device.
struct Cx<'a> {
    device: &'a Device,
    positions: Positions,
    place: Place,
}

type Res<T> = Result<T, ProfileError>;

impl Cx<'_> {
    fn refuse(&self, field: &'static str, allowed: String, value: String) -> ProfileError {
        ProfileError::Field {
            place: self.place.clone(),
            field,
            allowed,
            got: value,
        }
    }

    fn unit(&self) -> &'static str {
        self.device.units().position
    }

    /// A position in counts: round(x/Δ), or x itself in counts, within i32.
    fn position(&self, field: &'static str, x: f64) -> Res<i32> {
        let (lo, hi) = (f64::from(i32::MIN), f64::from(i32::MAX));
        match self.positions {
            Positions::Si => {
                let n = (x / self.device.resolution).round();
                if n.is_finite() && (lo..=hi).contains(&n) {
                    #[allow(clippy::cast_possible_truncation)]
                    return Ok(n as i32);
                }
                let reach = sig(hi * self.device.resolution);
                Err(self.refuse(
                    field,
                    format!(
                        "finite and within the encoder's range, ±{reach} {} (±2147483647 counts)",
                        self.unit()
                    ),
                    got(x),
                ))
            }
            Positions::Counts => {
                if x.is_finite() && x.fract() == 0.0 && (lo..=hi).contains(&x) {
                    #[allow(clippy::cast_possible_truncation)]
                    return Ok(x as i32);
                }
                Err(self.refuse(
                    field,
                    "a whole number of counts in [-2147483648, 2147483647]".into(),
                    got(x),
                ))
            }
        }
    }

    fn stiffness(&self, x: f64) -> Res<f32> {
        STIFFNESS
            .check("stiffness", x, self.device.rotational)
            .map_err(|e| self.refuse("stiffness", e.allowed().into(), got(x)))
            .map(narrow)
    }

    fn damping(&self, x: f64) -> Res<f32> {
        DAMPING
            .check("damping", x, self.device.rotational)
            .map_err(|e| self.refuse("damping", e.allowed().into(), got(x)))
            .map(narrow)
    }

    fn law(&self, text: &str) -> Res<DamperLaw> {
        text.parse()
            .map_err(|e| self.refuse("damper", format!("a damper law: {e}"), format!("{text:?}")))
    }

    fn element(&self, spec: &ElementSpec, origin: Origin, out: &mut Vec<Placed>) -> Res<()> {
        let mut push = |origin: Origin, element| out.push(Placed { origin, element });
        match spec {
            ElementSpec::Wall(w) => push(
                origin,
                ProfileElement::Wall {
                    position: self.position("at", w.at)?,
                    side: match w.side {
                        SideSpec::Upper => Side::Upper,
                        SideSpec::Lower => Side::Lower,
                    },
                    stiffness: self.stiffness(w.stiffness)?,
                    damping: self.damping(w.damping)?,
                    damper: self.law(&w.damper)?,
                },
            ),
            ElementSpec::EndStops(s) => {
                for (part, e) in ["lower", "upper"].into_iter().zip(self.end_stops(s)?) {
                    push(
                        Origin {
                            part: Some(part),
                            ..origin
                        },
                        e,
                    );
                }
            }
            ElementSpec::Detents(d) => push(origin, self.detents(d)?),
            ElementSpec::Spring(s) => push(
                origin,
                ProfileElement::Spring {
                    center: self.position("center", s.center)?,
                    stiffness: self.stiffness(s.stiffness)?,
                    damping: self.damping(s.damping)?,
                    damper: self.law(&s.damper)?,
                },
            ),
            ElementSpec::Viscous(v) => push(origin, self.viscous(v)?),
        }
        Ok(())
    }

    /// A lower wall at `min` and an upper wall at `max`, with free space between.
    fn end_stops(&self, s: &EndStopsSpec) -> Res<[ProfileElement; 2]> {
        let (lo, hi) = (self.position("min", s.min)?, self.position("max", s.max)?);
        let (stiffness, damping, damper) = (
            self.stiffness(s.stiffness)?,
            self.damping(s.damping)?,
            self.law(&s.damper)?,
        );
        if hi <= lo {
            return Err(self.refuse(
                "max",
                format!("above `min` by at least one count (`min` is count {lo})"),
                format!("{} (count {hi})", got(s.max)),
            ));
        }
        let wall = |position, side| ProfileElement::Wall {
            position,
            side,
            stiffness,
            damping,
            damper,
        };
        Ok([wall(lo, Side::Lower), wall(hi, Side::Upper)])
    }

    fn detents(&self, d: &DetentsSpec) -> Res<ProfileElement> {
        let first = self.position("first", d.first)?;
        if !(1..=u32::from(MAX_DETENTS)).contains(&d.count) {
            return Err(self.refuse(
                "count",
                format!("a whole number in [1, {MAX_DETENTS}]"),
                d.count.to_string(),
            ));
        }
        let pitch_counts = self.pitch(d)?;
        // The train spans [first − pitch/2, first + (count − ½)·pitch) counts: within i32.
        let ends = [
            f64::from(first) - pitch_counts / 2.0,
            f64::from(first) + (f64::from(d.count) - 0.5) * pitch_counts,
        ];
        if ends
            .iter()
            .any(|e| !(f64::from(i32::MIN)..=f64::from(i32::MAX)).contains(e))
        {
            return Err(self.refuse(
                "count",
                "small enough that the train ends inside the encoder's range (±2147483647 counts)"
                    .into(),
                d.count.to_string(),
            ));
        }
        if !(d.strength.is_finite() && (0.0..=MAX_STRENGTH).contains(&d.strength)) {
            return Err(self.refuse(
                "strength",
                format!(
                    "finite and in [0, {}] {}",
                    got(MAX_STRENGTH),
                    self.device.units().force
                ),
                got(d.strength),
            ));
        }
        Ok(ProfileElement::Detents {
            first,
            pitch_counts,
            #[allow(clippy::cast_possible_truncation)]
            count: d.count as u16,
            strength: narrow(d.strength),
            damping: self.damping(d.damping)?,
            damper: self.law(&d.damper)?,
        })
    }

    /// The pitch in counts from exactly one of `pitch` and `per_rev`, at least
    /// [`MIN_PITCH_COUNTS`].
    fn pitch(&self, d: &DetentsSpec) -> Res<f64> {
        let one_of = "exactly one of `pitch` and `per_rev`".to_owned();
        match (d.pitch, d.per_rev) {
            (Some(_), Some(_)) => Err(self.refuse("pitch", one_of, "both".into())),
            (None, None) => Err(self.refuse("pitch", one_of, "neither".into())),
            (None, Some(n)) if !self.device.rotational => Err(self.refuse(
                "per_rev",
                "only on a rotary axis (a linear axis gives `pitch`)".into(),
                got(n),
            )),
            (None, Some(n)) => {
                let cpr = self.device.counts_per_rev();
                let p = cpr / n;
                if n.is_finite() && n > 0.0 && p >= MIN_PITCH_COUNTS {
                    return Ok(p);
                }
                Err(self.refuse(
                    "per_rev",
                    format!(
                        "finite and in (0, {}] detents per revolution (a pitch of at least 2 \
                         counts of the {} per revolution)",
                        sig(cpr / MIN_PITCH_COUNTS),
                        sig(cpr)
                    ),
                    got(n),
                ))
            }
            (Some(p), None) => {
                let counts = match self.positions {
                    Positions::Si => p / self.device.resolution,
                    Positions::Counts => p,
                };
                if counts.is_finite() && counts >= MIN_PITCH_COUNTS {
                    return Ok(counts);
                }
                let min = match self.positions {
                    Positions::Si => format!(
                        "{} {}",
                        sig(MIN_PITCH_COUNTS * self.device.resolution),
                        self.unit()
                    ),
                    Positions::Counts => "2".to_owned(),
                };
                Err(self.refuse(
                    "pitch",
                    format!("finite and at least 2 counts ({min})"),
                    got(p),
                ))
            }
        }
    }

    fn viscous(&self, v: &ViscousSpec) -> Res<ProfileElement> {
        let (from, to) = (self.position("from", v.from)?, self.position("to", v.to)?);
        if to <= from {
            return Err(self.refuse(
                "to",
                format!("above `from` by at least one count (`from` is count {from}): the zone is empty"),
                format!("{} (count {to})", got(v.to)),
            ));
        }
        Ok(ProfileElement::Viscous {
            from,
            to,
            damping: self.damping(v.damping)?,
            damper: self.law(&v.damper)?,
        })
    }
}

/// A checked f64 as the wire's f32 (every checked range is inside f32's).
#[allow(clippy::cast_possible_truncation)]
fn narrow(x: f64) -> f32 {
    x as f32
}
