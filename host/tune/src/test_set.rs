//! The verification set: the release and impact tests a stiffness must pass, and how they
//! are chosen (no I/O here: `verify` runs them).
//!
//! **The verification set at stiffness K** (what a user does to a wall, up to the stated maximum
//! velocity v_max): with d(K) = round(v_max·√(m/K)/Δ) the deflection whose spring energy
//! ½K(dΔ)² equals the kinetic energy ½m·v_max² (at least 2 ticks),
//! - releases (Fig. 8) on the bidirectional wall from +d and −d (full energy) and from
//!   ±max(2, ⌈d/2⌉) (a quarter of it): each swing through the wall is an impact from one side
//!   at a velocity up to v_max, and the release is a user letting go while pressing;
//! - impacts ([`HostMsg::Impact`](stiffwall_proto::HostMsg::Impact): the firmware launches the
//!   device at a velocity toward the wall and releases it at contact): on a one-sided wall from
//!   its free side at v_max and v_max/2, and through the bidirectional wall from both sides at
//!   v_max, 0.8 v_max and 0.6 v_max ([`BOTH_SIDES_IMPACT_SHARES`]); the launch starts [`launch_distance`] ticks away. When the wall being tuned is
//!   one-sided (the user's config), the bidirectional impacts are left out: that wall is never
//!   hit from its far side, and a one-sided impact that throws the device out faster than it
//!   came already fails;
//! - when the model does not fit the device (`thorough`), also releases from ±max(2, ⌈d/4⌉)
//!   (a sixteenth of the energy) and an impact at v_max/4, and every test runs twice as long.
//!
//! A K passes when every test of the set passes by [`super::verdict`]: the wall comes to rest
//! (`stiffwall_core::rest`); chatter within one count, a buzz over more counts and growth fail
//! (chatter passes, reported, only under `Criterion::AcceptChatter`). An impact
//! whose launch did not deliver the device to the wall at the requested speed (never reached
//! it, arrived slower than asked, or more than
//! [`LAUNCH_EXCUSE_FACTOR`](super::launch::LAUNCH_EXCUSE_FACTOR) × faster, see
//! [`super::launch`]: the firmware's damped hold cannot move a device whose μ = m/(KT²) is
//! small) and then failed says nothing about the wall ([`Verdict::NotLaunched`]); it is judged
//! by the releases of the set, which reach the same energy from both sides, and reported. (A
//! launch faster than asked that passes, a harder test, passes.)
//!
//! Units: effective ticks (counts after the config's coarsening), ticks per servo tick.

use super::verdict::MIN_TAIL;

/// One test of the verification set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Test {
    /// Hold at `deflection_ticks` effective ticks from the wall, release.
    Release {
        /// Signed deflection, effective ticks.
        deflection_ticks: i32,
    },
    /// Launch from `start_ticks` at `velocity_milliticks` (effective ticks per 1000 servo
    /// ticks) toward the wall, released at contact.
    Impact {
        /// Start, effective ticks from the wall.
        start_ticks: i32,
        /// Launch velocity, effective ticks per 1000 ticks, toward the wall.
        velocity_milliticks: i32,
        /// One-sided wall (occupying counts ≥ 0) instead of the bidirectional one.
        one_sided: bool,
    },
}

impl Test {
    /// One line for the report.
    #[must_use]
    pub fn describe(&self) -> String {
        match *self {
            Test::Release { deflection_ticks } => format!("release {deflection_ticks:+}"),
            Test::Impact {
                velocity_milliticks,
                one_sided,
                ..
            } => format!(
                "impact {:+.2} ticks/tick{}",
                f64::from(velocity_milliticks) / 1000.0,
                if one_sided { " (one-sided)" } else { "" }
            ),
        }
    }
}

/// Distance, effective ticks, from which an impact at `v_ticks` ticks per servo tick is
/// launched: enough for the hold spring to bring the device to speed (the larger of 20 ticks
/// and one natural period `natural_ticks`, plus the spring's lag of two ticks of motion).
#[must_use]
pub fn launch_distance(v_ticks: f64, natural_ticks: f64) -> i32 {
    (v_ticks.abs() * (natural_ticks.max(20.0) + 2.0))
        .ceil()
        .clamp(3.0, f64::from(1 << 20)) as i32
}

/// Where the wall of an impact test is: on both sides of the wall position (the bidirectional
/// wall), or only on the side of counts ≥ 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WallSides {
    /// The bidirectional wall.
    Both,
    /// A one-sided wall, occupying counts ≥ 0.
    OneSided,
}

/// An impact test at `v_ticks` ticks per tick (sign: direction of motion), launched from the
/// side it moves away from, into a wall on `sides`.
#[must_use]
pub fn impact(v_ticks: f64, natural_ticks: f64, sides: WallSides) -> Test {
    let one_sided = sides == WallSides::OneSided;
    let milli = ((v_ticks * 1000.0).round() as i32).clamp(-1_000_000, 1_000_000);
    let milli = if milli == 0 { 1 } else { milli };
    let d = launch_distance(v_ticks, natural_ticks);
    Test::Impact {
        start_ticks: if milli > 0 { -d } else { d },
        velocity_milliticks: milli,
        one_sided,
    }
}

/// Speeds, shares of v, of the verification's impacts through a bidirectional wall from both
/// sides. A damped wall's failing bands are narrow: on maxon-re35-amp-3khz at B = 4.5e-3 a
/// wall 1.02 × K*(B) passed impacts at v and every release, and buzzed by the truth only after
/// impacts at 0.8 v (the truth's grid runs 0.1 v … v).
pub const BOTH_SIDES_IMPACT_SHARES: [f64; 3] = [1.0, 0.8, 0.6];

/// The verification set for full-energy deflection `d`, maximum velocity `v_ticks` (ticks per
/// servo tick) and natural period `natural_ticks` (see the module header); `impacts`: the
/// device runs impact tests; `one_sided_wall`: the wall being tuned is one-sided.
#[must_use]
pub fn test_set(
    d: i32,
    v_ticks: f64,
    natural_ticks: f64,
    thorough: bool,
    impacts: bool,
    one_sided_wall: bool,
) -> Vec<Test> {
    let d = d.abs().max(2);
    let mut levels = vec![d, ((d + 1) / 2).max(2)];
    if thorough {
        levels.push(((d + 3) / 4).max(2));
    }
    levels.dedup();
    let mut set: Vec<Test> = levels
        .into_iter()
        .flat_map(|l| [l, -l])
        .map(|deflection_ticks| Test::Release { deflection_ticks })
        .collect();
    if impacts {
        let v = v_ticks.abs();
        set.push(impact(v, natural_ticks, WallSides::OneSided));
        set.push(impact(v / 2.0, natural_ticks, WallSides::OneSided));
        if thorough {
            set.push(impact(v / 4.0, natural_ticks, WallSides::OneSided));
        }
        if !one_sided_wall {
            for share in BOTH_SIDES_IMPACT_SHARES {
                set.push(impact(share * v, natural_ticks, WallSides::Both));
                set.push(impact(-share * v, natural_ticks, WallSides::Both));
            }
        }
    }
    set
}

/// Minimum constant run for [`settled_at`]: three natural periods 2π√(m/K)/T, at least
/// 2·[`MIN_TAIL`] ticks.
#[must_use]
pub fn min_settle_run(mass: f64, k: f64, period_s: f64) -> usize {
    let natural = std::f64::consts::TAU * (mass / k).sqrt() / period_s;
    ((3.0 * natural) as usize).max(2 * MIN_TAIL)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_set_has_both_sides_at_two_or_three_energies() {
        let s = test_set(12, 5.0, 14.0, false, false, false);
        assert_eq!(
            s,
            [12, -12, 6, -6].map(|d| Test::Release {
                deflection_ticks: d
            })
        );
        let s = test_set(12, 5.0, 14.0, true, false, false);
        assert_eq!(s.len(), 6);
        assert_eq!(
            test_set(2, 5.0, 14.0, true, false, false).len(),
            2,
            "levels never repeat"
        );
        let s = test_set(12, 5.0, 14.0, false, true, false);
        assert_eq!(s.len(), 12);
        // Impacts from the free side of the one-sided wall at v and v/2, through the
        // bidirectional wall from both sides, always launched toward the wall.
        assert_eq!(
            s[4],
            Test::Impact {
                start_ticks: -110,
                velocity_milliticks: 5000,
                one_sided: true
            }
        );
        assert!(s[4..].iter().all(
            |t| matches!(t, Test::Impact { start_ticks, velocity_milliticks, .. }
            if start_ticks.signum() == -velocity_milliticks.signum())
        ));
        assert!(matches!(
            s[7],
            Test::Impact {
                start_ticks: 110,
                one_sided: false,
                ..
            }
        ));
        // Through the bidirectional wall also at 0.8 v and 0.6 v, from both sides.
        assert!(matches!(
            s[8..],
            [
                Test::Impact {
                    velocity_milliticks: 4000,
                    one_sided: false,
                    ..
                },
                Test::Impact {
                    velocity_milliticks: -4000,
                    ..
                },
                Test::Impact {
                    velocity_milliticks: 3000,
                    ..
                },
                Test::Impact {
                    velocity_milliticks: -3000,
                    ..
                }
            ]
        ));
        // A one-sided wall being tuned: only impacts from its free side.
        let s = test_set(12, 5.0, 14.0, false, true, true);
        assert_eq!(s.len(), 6);
        assert!(s[4..].iter().all(|t| matches!(
            t,
            Test::Impact {
                one_sided: true,
                ..
            }
        )));
        assert!(test_set(0, 5.0, 14.0, false, false, false).iter().all(
            |t| matches!(t, Test::Release { deflection_ticks } if deflection_ticks.abs() == 2)
        ));
    }
}
