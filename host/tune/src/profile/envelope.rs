//! What a tune verified about a device, as the check uses it: the (K, B) frontier (each B
//! tried, its damper law and largest resting K*), the margin the tune applied, the quiet
//! ceiling 2·max(c, F_s)/Δ, Δ and the friction. [`Envelope::limit`] is the stiffness an
//! element may have at its damping B:
//!
//! K_limit(B) = min(margin × K*(B), quiet ceiling).
//!
//! K*(B) is a verified point's K where B is a B the tune tried (within [`B_MATCH`], 1 %, so a
//! B copied from the tune's report, or from another tune of the same device, is that B); between two tried B's it
//! is the SMALLER of the two points' K: the frontier is not monotone in B (a damper helps, then
//! past its best B destabilises) and nothing between two tests was verified, so the smaller is
//! the one both sides support. Above the largest B tried (of the element's damper law) nothing
//! was verified: no limit. B = 0 points hold for every law (the damper does nothing at B = 0).
//!
//! Units: the device's (N/m, N·s/m, N, m; N·m/rad, N·m·s/rad, N·m, rad).

use super::units::Device;
use crate::outcome::Outcome;
use serde::Serialize;
use stiffwall_proto::DamperLaw;

/// Relative distance within which a B counts as a tried B: 1 %. A tune's B is scaled from
/// its identified spring-only K, so two tunes of one device set B's a little apart (maxon-re35
/// 5.4617e-3 and 5.4662e-3, 0.08 %, before and after a change of the identification's probe)
/// and a profile copying one tune's B would fail the other's check at 0.1 %. Within 1 % of
/// the tune's B the exact linear K_max(B) moves by 0.07 % (maxon-re35 at 5.466e-3) to 0.9 %
/// (phantom-1.0 at 4.058, below its best B), well inside the tune's margin (×0.8) that the
/// limit applies.
pub const B_MATCH: f64 = 1e-2;

/// One tried B of the frontier.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Point {
    /// B, N·s/m (N·m·s/rad).
    pub b: f64,
    /// Largest resting K at B, N/m (N·m/rad); None: the tune found none at or above its best.
    pub k: Option<f64>,
    /// The damper's law at this B.
    #[serde(serialize_with = "law_name")]
    pub damper: DamperLaw,
}

fn law_name<S: serde::Serializer>(law: &DamperLaw, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(law)
}

/// What a tune verified (module header).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Envelope {
    /// Where it was measured (`maxon-re35`, a plant file, a tune JSON file).
    pub source: String,
    /// The device: Δ and its axis.
    pub device: Device,
    /// The frontier in the tune's order.
    pub frontier: Vec<Point>,
    /// The margin the tune applied to the set wall's K (`margin_used`).
    pub margin: f64,
    /// 2·max(c, F_s)/Δ, N/m (N·m/rad); 0: no friction identified, no ceiling.
    pub quiet_ceiling: f64,
    /// The identified Coulomb friction c, N (N·m).
    pub coulomb: f64,
    /// Static friction F_s = max(c, quiet ceiling·Δ/2), N (N·m).
    pub static_friction: f64,
    /// The device's largest force, N (N·m): its largest output code × force per code, the
    /// most a detent's strength A may be (the firmware refuses more). None when unknown (a
    /// saved tune result, which does not record it).
    pub force_limit: Option<f64>,
}

/// Where an element's K*(B) comes from.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "from", rename_all = "snake_case")]
pub enum Verified {
    /// A tried B.
    At {
        /// The tried B.
        b: f64,
        /// Its largest resting K.
        k: f64,
    },
    /// Between two tried B's: the smaller K.
    Between {
        /// The tried B below.
        b_lo: f64,
        /// Its K.
        k_lo: f64,
        /// The tried B above.
        b_hi: f64,
        /// Its K.
        k_hi: f64,
    },
    /// Above the largest B tried with the law: nothing verified.
    AboveTried {
        /// The largest B tried with the law.
        b_max: f64,
        /// The law.
        law: String,
    },
    /// A bracketing point found no K (or no tried B below this one).
    Unverified {
        /// That point's B.
        b: f64,
    },
}

impl Verified {
    /// K*(B), when verified.
    #[must_use]
    pub fn k_star(&self) -> Option<f64> {
        match *self {
            Self::At { k, .. } => Some(k),
            Self::Between { k_lo, k_hi, .. } => Some(k_lo.min(k_hi)),
            Self::AboveTried { .. } | Self::Unverified { .. } => None,
        }
    }
}

impl Envelope {
    /// The envelope of a tune's result, measured on `source`.
    #[must_use]
    pub fn from_outcome(o: &Outcome, source: impl Into<String>) -> Self {
        let device = Device {
            rotational: o.params.rotational,
            resolution: o.params.resolution,
        };
        let coulomb = o.identified.coulomb[0];
        Self {
            source: source.into(),
            device,
            frontier: o
                .frontier
                .iter()
                .map(|p| Point {
                    b: p.b,
                    k: p.k_verified,
                    damper: p.damper,
                })
                .collect(),
            margin: o.margin_used,
            quiet_ceiling: o.quiet_ceiling,
            coulomb,
            static_friction: coulomb.max(o.quiet_ceiling * device.resolution / 2.0),
            force_limit: None,
        }
    }

    /// The same envelope on a device whose largest force is `force_limit` N (N·m).
    #[must_use]
    pub fn with_force_limit(self, force_limit: f64) -> Self {
        Self {
            force_limit: Some(force_limit),
            ..self
        }
    }

    /// K*(B) at damping `b` whose non-zero parts use `laws` (the most restrictive law's).
    #[must_use]
    pub fn verified(&self, b: f64, laws: &[DamperLaw]) -> Verified {
        if b == 0.0 || laws.is_empty() {
            return self.verified_with(b, None);
        }
        let each = laws.iter().map(|&l| self.verified_with(b, Some(l)));
        each.min_by(|x, y| match (x.k_star(), y.k_star()) {
            (None, _) => std::cmp::Ordering::Less,
            (_, None) => std::cmp::Ordering::Greater,
            (Some(a), Some(c)) => a.total_cmp(&c),
        })
        .unwrap_or(Verified::Unverified { b })
    }

    /// The K limit at damping `b` (module header) and where K* came from; None: nothing
    /// verified there.
    #[must_use]
    pub fn limit(&self, b: f64, laws: &[DamperLaw]) -> (Verified, Option<f64>) {
        let v = self.verified(b, laws);
        let limit = v.k_star().map(|k| {
            let k = self.margin * k;
            if self.quiet_ceiling > 0.0 {
                k.min(self.quiet_ceiling)
            } else {
                k
            }
        });
        (v, limit)
    }

    /// K*(B) from the points of `law` (and every B = 0 point); `law` None: B = 0 only.
    fn verified_with(&self, b: f64, law: Option<DamperLaw>) -> Verified {
        // The points of the law by B, one per B (the smaller K, None first: unverified).
        let mut pts: Vec<(f64, Option<f64>)> = Vec::new();
        for p in &self.frontier {
            if p.b != 0.0 && Some(p.damper) != law {
                continue;
            }
            match pts.iter_mut().find(|(b, _)| *b == p.b) {
                Some(q) => q.1 = q.1.zip(p.k).map(|(x, y)| x.min(y)),
                None => pts.push((p.b, p.k)),
            }
        }
        pts.sort_by(|x, y| x.0.total_cmp(&y.0));
        let at = |(pb, k): (f64, Option<f64>)| match k {
            Some(k) => Verified::At { b: pb, k },
            None => Verified::Unverified { b: pb },
        };
        if let Some(&p) = pts.iter().find(|p| (b - p.0).abs() <= B_MATCH * p.0) {
            return at(p);
        }
        let Some(&(b_max, _)) = pts.last() else {
            return Verified::Unverified { b };
        };
        if b > b_max {
            return Verified::AboveTried {
                b_max,
                law: law.map_or_else(|| "any".to_owned(), |l| l.to_string()),
            };
        }
        let hi = pts.iter().position(|p| p.0 > b).unwrap_or(pts.len() - 1);
        let Some(lo) = hi.checked_sub(1).map(|i| pts[i]) else {
            return Verified::Unverified { b: pts[hi].0 };
        };
        match (lo.1, pts[hi].1) {
            (Some(k_lo), Some(k_hi)) => Verified::Between {
                b_lo: lo.0,
                k_lo,
                b_hi: pts[hi].0,
                k_hi,
            },
            (None, _) => Verified::Unverified { b: lo.0 },
            (_, None) => Verified::Unverified { b: pts[hi].0 },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DB1: DamperLaw = DamperLaw::DeadBand { counts: 1 };

    /// A frontier written by hand: K* 1.3 at B = 0, 4.7 at 0.005 (dead-band-1), 2.0 at 0.01
    /// (dead-band-1), 6.0 at 0.004 (difference); margin 0.8, quiet ceiling 5.
    fn env() -> Envelope {
        let p = |b, k, damper| Point { b, k, damper };
        Envelope {
            source: "hand".into(),
            device: Device {
                rotational: true,
                resolution: 1e-3,
            },
            frontier: vec![
                p(0.0, Some(1.3), DB1),
                p(0.005, Some(4.7), DB1),
                p(0.01, Some(2.0), DB1),
                p(0.004, Some(6.0), DamperLaw::Difference),
            ],
            margin: 0.8,
            quiet_ceiling: 5.0,
            coulomb: 0.002,
            static_friction: 0.0025,
            force_limit: None,
        }
    }

    #[test]
    fn at_a_tried_b_the_margin_and_the_ceiling_apply() {
        let e = env();
        // B = 0: 0.8 × 1.3 = 1.04 (any law).
        let (v, k) = e.limit(0.0, &[]);
        assert_eq!(v, Verified::At { b: 0.0, k: 1.3 });
        assert!((k.unwrap() - 1.04).abs() < 1e-12);
        // B = 0.005: 0.8 × 4.7 = 3.76 < 5.
        assert!((e.limit(0.005, &[DB1]).1.unwrap() - 3.76).abs() < 1e-12);
        // 0.00504 is within 1 % of 0.005: that point; 0.00506 (1.2 %) is not, and lies
        // between 0.005 (4.7) and 0.01 (2.0): the smaller, 0.8 × 2.0.
        assert!((e.limit(0.005_04, &[DB1]).1.unwrap() - 3.76).abs() < 1e-12);
        assert!((e.limit(0.005_06, &[DB1]).1.unwrap() - 1.6).abs() < 1e-12);
        // difference at 0.004: 0.8 × 6 = 4.8 < 5; a ceiling of 4 caps it.
        let mut capped = env();
        capped.quiet_ceiling = 4.0;
        assert_eq!(capped.limit(0.004, &[DamperLaw::Difference]).1, Some(4.0));
    }

    #[test]
    fn between_two_tried_b_the_smaller_k() {
        let e = env();
        // (0, 1.3) and (0.005, 4.7): 1.3, limit 1.04.
        let (v, k) = e.limit(0.003, &[DB1]);
        assert_eq!(v.k_star(), Some(1.3));
        assert!((k.unwrap() - 1.04).abs() < 1e-12);
        // (0.005, 4.7) and (0.01, 2.0): 2.0, limit 1.6 (not monotone).
        assert!((e.limit(0.007, &[DB1]).1.unwrap() - 1.6).abs() < 1e-12);
        // Both laws: the more restrictive (dead-band-1 at 0.003: 1.3; difference: 1.3 too).
        assert_eq!(
            e.verified(0.003, &[DB1, DamperLaw::Difference]).k_star(),
            Some(1.3)
        );
    }

    #[test]
    fn above_the_largest_b_tried_nothing_is_verified() {
        let e = env();
        let (v, k) = e.limit(0.0102, &[DB1]); // 2 % above 0.01: beyond B_MATCH.
        assert_eq!(k, None);
        assert_eq!(
            v,
            Verified::AboveTried {
                b_max: 0.01,
                law: "dead-band-1".into()
            }
        );
        // The difference law was tried up to 0.004 only.
        assert_eq!(e.limit(0.005, &[DamperLaw::Difference]).1, None);
        // A law never tried: only B = 0.
        assert_eq!(e.limit(0.001, &[DamperLaw::DeadBand { counts: 2 }]).1, None);
    }

    #[test]
    fn a_point_without_k_verifies_nothing_around_it() {
        let mut e = env();
        e.frontier[1].k = None;
        assert_eq!(
            e.limit(0.003, &[DB1]),
            (Verified::Unverified { b: 0.005 }, None)
        );
        assert_eq!(e.limit(0.005, &[DB1]).1, None);
    }
}
