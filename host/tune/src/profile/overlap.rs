//! Where each wire element acts, in raw counts, and the overlaps that make no sense: two walls
//! on the same side, a lower wall at or above an upper wall (no free space between), two detent
//! trains sharing a count. Other overlaps (a viscous zone over detents, a spring with walls)
//! are allowed: their forces add, and so do their stiffness and damping in the check.
//!
//! Units: raw counts (count n spans [nΔ, (n+1)Δ); the effective count equals the raw one when
//! the servo's coarsening shift is 0, the host's assumption).

use super::error::ProfileError;
use super::placed::Placed;
use stiffwall_proto::{ProfileElement, Side};

/// The counts an element acts on, inclusive; None: unbounded on that side.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Span {
    /// First count, None: from −∞.
    pub lo: Option<i64>,
    /// Last count, None: to +∞.
    pub hi: Option<i64>,
}

impl Span {
    /// Whether the two spans share a count.
    #[must_use]
    pub fn meets(&self, other: &Span) -> bool {
        let lo = self
            .lo
            .unwrap_or(i64::MIN)
            .max(other.lo.unwrap_or(i64::MIN));
        let hi = self
            .hi
            .unwrap_or(i64::MAX)
            .min(other.hi.unwrap_or(i64::MAX));
        lo <= hi
    }
}

/// Where `e` exerts a force (the module header of `stiffwall_proto::profile`): an upper wall on
/// counts ≥ position, a lower one on counts < position, a spring everywhere, a detent train on
/// the counts n whose centre n + ½ lies in [first − pitch/2, first + (count − ½)·pitch), a
/// viscous zone on [from, to).
#[must_use]
pub fn span(e: &ProfileElement) -> Span {
    match *e {
        ProfileElement::Wall {
            position,
            side: Side::Upper,
            ..
        } => Span {
            lo: Some(i64::from(position)),
            hi: None,
        },
        ProfileElement::Wall { position, .. } => Span {
            lo: None,
            hi: Some(i64::from(position) - 1),
        },
        ProfileElement::Spring { .. } => Span { lo: None, hi: None },
        ProfileElement::Detents {
            first,
            pitch_counts,
            count,
            ..
        } => {
            let f = f64::from(first) - 0.5;
            // Checked within i32 by the lowering.
            #[allow(clippy::cast_possible_truncation)]
            let lo = (f - pitch_counts / 2.0).ceil() as i64;
            #[allow(clippy::cast_possible_truncation)]
            let hi = (f + (f64::from(count) - 0.5) * pitch_counts).ceil() as i64 - 1;
            Span {
                lo: Some(lo),
                hi: Some(hi),
            }
        }
        ProfileElement::Viscous { from, to, .. } => Span {
            lo: Some(i64::from(from)),
            hi: Some(i64::from(to) - 1),
        },
    }
}

/// Refuses the overlaps that make no sense (module header), naming both elements.
///
/// # Errors
/// [`ProfileError::Overlap`] for the first such pair in file order.
pub fn refuse_nonsense(elements: &[Placed]) -> Result<(), ProfileError> {
    let refuse = |a: &Placed, b: &Placed, why: String| ProfileError::Overlap {
        first: a.origin.place(),
        second: b.origin.place(),
        why,
    };
    for (i, a) in elements.iter().enumerate() {
        for b in &elements[i + 1..] {
            match (a.element, b.element) {
                (
                    ProfileElement::Wall {
                        position: pa,
                        side: sa,
                        ..
                    },
                    ProfileElement::Wall {
                        position: pb,
                        side: sb,
                        ..
                    },
                ) => {
                    if let Some(why) = walls(pa, sa, pb, sb) {
                        return Err(refuse(a, b, why));
                    }
                }
                (ProfileElement::Detents { .. }, ProfileElement::Detents { .. }) => {
                    let (sa, sb) = (span(&a.element), span(&b.element));
                    if sa.meets(&sb) {
                        return Err(refuse(
                            a,
                            b,
                            format!(
                                "two detent trains overlap (counts {} and {}): a train's \
                                 minima would be shifted by the other's force; join them or \
                                 leave a gap",
                                counts(sa),
                                counts(sb)
                            ),
                        ));
                    }
                }
                _ => {}
            }
        }
    }
    Ok(())
}

/// Why two walls make no sense together, or None.
fn walls(pa: i32, sa: Side, pb: i32, sb: Side) -> Option<String> {
    if sa == sb {
        let side = if sa == Side::Upper { "upper" } else { "lower" };
        return Some(format!(
            "two {side} walls (at counts {pa} and {pb}): a profile has at most one wall on each \
             side (the outer one is never reached)"
        ));
    }
    let (lower, upper) = if sa == Side::Lower {
        (pa, pb)
    } else {
        (pb, pa)
    };
    (lower >= upper).then(|| {
        format!(
            "the lower wall occupies the counts below {lower} and the upper wall the counts from \
             {upper} on: no free space between them (the lower wall's surface must be below the \
             upper wall's)"
        )
    })
}

/// A span in words: `a..=b`.
#[must_use]
pub fn counts(s: Span) -> String {
    let end = |x: Option<i64>, inf: &str| x.map_or_else(|| inf.to_owned(), |n| n.to_string());
    format!("{}..={}", end(s.lo, "-∞"), end(s.hi, "+∞"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use stiffwall_proto::DamperLaw;

    fn detents(first: i32, pitch_counts: f64, count: u16) -> ProfileElement {
        ProfileElement::Detents {
            first,
            pitch_counts,
            count,
            strength: 1.0,
            damping: 0.0,
            damper: DamperLaw::default(),
        }
    }

    /// 13 minima every 8192/24 = 341.33 counts from 0: the centres n + ½ in
    /// [−170.67, 12.5 × 341.33 = 4266.67): n from −171 (−170.5) to 4266 (4266.5).
    #[test]
    fn a_detent_train_spans_half_a_pitch_past_its_ends() {
        let s = span(&detents(0, 8192.0 / 24.0, 13));
        assert_eq!((s.lo, s.hi), (Some(-171), Some(4266)));
        // Pitch 4 from count 10, 2 minima: centres in [8, 16): n + ½ ≥ 8 → n ≥ 8 (7.5 is out),
        // n + ½ < 16 → n ≤ 15.
        let s = span(&detents(10, 4.0, 2));
        assert_eq!((s.lo, s.hi), (Some(8), Some(15)));
    }

    #[test]
    fn walls_need_free_space_and_one_per_side() {
        assert!(walls(-10, Side::Lower, 10, Side::Upper).is_none());
        assert!(
            walls(9, Side::Lower, 10, Side::Upper).is_none(),
            "one free count"
        );
        assert!(walls(10, Side::Lower, 10, Side::Upper)
            .unwrap()
            .contains("no free space"));
        assert!(walls(10, Side::Upper, 11, Side::Lower)
            .unwrap()
            .contains("no free space"));
        assert!(walls(1, Side::Upper, 50, Side::Upper)
            .unwrap()
            .contains("two upper walls"));
    }

    #[test]
    fn spans_meet_when_they_share_a_count() {
        let a = Span {
            lo: Some(0),
            hi: Some(9),
        };
        let b = Span {
            lo: Some(9),
            hi: None,
        };
        let c = Span {
            lo: Some(10),
            hi: None,
        };
        assert!(a.meets(&b));
        assert!(!a.meets(&c));
        assert_eq!(counts(b), "9..=+∞");
    }
}
