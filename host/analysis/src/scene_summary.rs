//! The one-screen summary of a simulated scene (`hostctl simulate`): the verdict by the rest
//! rule of `stiffwall_core::rest` and the energy audit of eqs. (26)–(29) and (35).
//!
//! Units: Table I (τ in sampling periods, ξ in ticks, energies in K·Δ²); a physical scene's
//! energies are also given in J (J·rad⁻¹·rad² = J on a rotary device: K·Δ² is N·m/rad · rad²).
//!
//! Invariants: [`SceneSummary::add`] takes every row in order (period 0 first) and keeps O(1)
//! memory whatever the run's length: the judged window of the rest rule is known before the run
//! (its start depends only on the run's length and the natural period 2π√μ periods), so only its
//! count changes and its lowest and highest count are kept. The energy sums start at period 1
//! (period 0 has no previous period). Nothing here prints.

use std::fmt::Write as _;
use stiffwall_core::rest;
use stiffwall_sim::scene::{Row, Scene};

/// What the run did, by the rest rule over its judged window.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Verdict {
    /// At most `rest::REST_MAX_CHANGES` count changes in the window; the last count.
    Rests {
        /// The count n = ⌊ξ⌋ at the end.
        count: i64,
    },
    /// It does not rest but stays within two neighbouring counts.
    Chatter {
        /// Count changes in the window.
        changes: u64,
    },
    /// H_T at the end above [`GROWTH_FACTOR`] × H_T(0): the oscillation grew.
    Growing,
    /// It keeps moving over more than two counts without growing: a limit cycle or a buzz.
    Persistent {
        /// Lowest and highest count of the window.
        counts: (i64, i64),
    },
    /// The solver stopped before the scene's last period (|ξ| beyond 1e150).
    Diverged {
        /// The last period reached.
        period: u64,
    },
}

/// H_T(end) / H_T(0) above which a run that does not rest counts as growing.
pub const GROWTH_FACTOR: f64 = 10.0;

/// Accumulates the summary of one run, a row at a time.
#[derive(Debug, Clone)]
pub struct SceneSummary {
    window_from: u64,
    periods: u64,
    first: Option<Row>,
    last: Option<Row>,
    prev_count: Option<i64>,
    changes: u64,
    lo: i64,
    hi: i64,
    h_max: f64,
    e_d: f64,
    e_g: f64,
    residual_sum: f64,
    residual_worst: f64,
}

fn count_of(xi: f64) -> i64 {
    // Saturating float-to-int conversion: a diverging ξ is reported by the verdict anyway.
    xi.floor() as i64
}

impl SceneSummary {
    /// An empty summary for a run of `scene`.
    #[must_use]
    pub fn new(scene: &Scene) -> Self {
        let len = usize::try_from(scene.periods.saturating_add(1)).unwrap_or(usize::MAX);
        let natural = 2.0 * std::f64::consts::PI * scene.params.mu.sqrt();
        Self {
            window_from: rest::window_start(len, natural) as u64,
            periods: scene.periods,
            first: None,
            last: None,
            prev_count: None,
            changes: 0,
            lo: i64::MAX,
            hi: i64::MIN,
            h_max: 0.0,
            e_d: 0.0,
            e_g: 0.0,
            residual_sum: 0.0,
            residual_worst: 0.0,
        }
    }

    /// Takes the next row.
    pub fn add(&mut self, r: &Row) {
        if self.first.is_none() {
            self.first = Some(*r);
        } else {
            self.e_d += r.e_d;
            self.e_g += r.e_g;
            self.residual_sum += r.residual;
            self.residual_worst = self.residual_worst.max(r.residual.abs());
        }
        self.last = Some(*r);
        self.h_max = self.h_max.max(r.h_t);
        if r.period >= self.window_from {
            let n = count_of(r.xi);
            if self.prev_count.is_some_and(|p| p != n) {
                self.changes += 1;
            }
            self.prev_count = Some(n);
            self.lo = self.lo.min(n);
            self.hi = self.hi.max(n);
        }
    }

    /// The verdict of the rows so far (`None` before the first row).
    #[must_use]
    pub fn verdict(&self) -> Option<Verdict> {
        let (first, last) = (self.first?, self.last?);
        if last.period < self.periods {
            return Some(Verdict::Diverged {
                period: last.period,
            });
        }
        let changes = self.changes;
        Some(if changes <= rest::REST_MAX_CHANGES as u64 {
            Verdict::Rests {
                count: count_of(last.xi),
            }
        } else if self.hi - self.lo <= 1 {
            Verdict::Chatter { changes }
        } else if first.h_t > 0.0 && last.h_t > GROWTH_FACTOR * first.h_t {
            Verdict::Growing
        } else {
            Verdict::Persistent {
                counts: (self.lo, self.hi),
            }
        })
    }

    /// The summary as text, a dozen lines. `joules_per_unit` is K·Δ² in J for a physical scene
    /// (energies are then also given in J), `None` for a dimensionless one.
    #[must_use]
    pub fn render(&self, joules_per_unit: Option<f64>) -> String {
        let mut out = String::new();
        let (Some(first), Some(last), Some(v)) = (self.first, self.last, self.verdict()) else {
            return "no period simulated\n".to_owned();
        };
        let window = last.period.saturating_sub(self.window_from) + 1;
        let verdict = match v {
            Verdict::Rests { count } => format!("comes to rest at count {count} (ξ = {:.4})", last.xi),
            Verdict::Chatter { changes } => format!(
                "chatter: does not rest, toggles between counts {} and {} ({changes} changes in the last {window} periods)",
                self.lo, self.hi
            ),
            Verdict::Growing => format!(
                "growing: H_T(end) = {:.3e} × H_T(0)",
                last.h_t / first.h_t
            ),
            Verdict::Persistent { counts: (lo, hi) } => format!(
                "persistent oscillation over counts {lo}..{hi} in the last {window} periods (a limit cycle or a buzz): does not rest"
            ),
            Verdict::Diverged { period } => format!("diverged at period {period} (|ξ| beyond 1e150)"),
        };
        let _ = writeln!(out, "verdict: {verdict}");
        let _ = writeln!(
            out,
            "  judged over periods {}..{} by the rest rule (at most {} count changes)",
            self.window_from,
            last.period,
            rest::REST_MAX_CHANGES
        );
        let _ = writeln!(
            out,
            "  end: τ = {} periods, ξ = {:.4} ticks, ξ̇ = {:.4} ticks/period",
            last.period, last.xi, last.xidot
        );
        self.render_energy(&mut out, first, last, joules_per_unit);
        out
    }

    fn render_energy(&self, out: &mut String, first: Row, last: Row, j: Option<f64>) {
        let unit = |x: f64| match j {
            Some(j) => format!("{x:.4e} K·Δ² ({:.4e} J)", x * j),
            None => format!("{x:.4e} K·Δ²"),
        };
        let _ = writeln!(out, "energy audit (26): ΔH_T + ΣE_d − ΣE_g = Σ residual");
        let _ = writeln!(
            out,
            "  H_T (35): start {}, end {}, largest {}",
            unit(first.h_t),
            unit(last.h_t),
            unit(self.h_max)
        );
        let _ = writeln!(
            out,
            "  ΣE_d (28), dissipated by b and c: {}",
            unit(self.e_d)
        );
        let _ = writeln!(
            out,
            "  ΣE_g (29), generated by the sampled wall: {}",
            unit(self.e_g)
        );
        let _ = writeln!(
            out,
            "  Σ residual: {} (largest in one period {:.3e} K·Δ²)",
            unit(self.residual_sum),
            self.residual_worst
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(text: &str) -> Scene {
        Scene::from_toml(text).unwrap()
    }

    fn summary_of(s: &Scene) -> SceneSummary {
        let mut sum = SceneSummary::new(s);
        s.simulate(&mut |r: &Row| sum.add(r)).unwrap();
        sum
    }

    const REGION: &str = "[device]\nmu = 100.0\nbeta = BETA\nsigma = SIGMA\n[controller]\ntau_d = 0.0\n[effects]\nzoh = true\nquantization = true\ncoulomb = true\nviscous = true\ndelay = false\none_sided_wall = false\namplifier = { kind = \"none\" }\nhand = { kind = \"none\" }\n[initial]\nxi = 0.0\nxidot = 5.0\n[run]\nperiods = 4000\nsolver = { kind = \"exact\" }\n";

    fn region(beta: f64, sigma: f64) -> Scene {
        scene(
            &REGION
                .replace("BETA", &beta.to_string())
                .replace("SIGMA", &sigma.to_string()),
        )
    }

    /// Region A of Fig. 3 (β ≥ ½, σ ≥ ½): eq. (17)–(18) guarantee rest.
    #[test]
    fn region_a_rests_and_the_audit_balances() {
        let s = summary_of(&region(1.0, 1.0));
        assert!(matches!(s.verdict(), Some(Verdict::Rests { .. })), "{s:?}");
        // (26) over the whole run: ΔH_T + ΣE_d − ΣE_g = Σ residual ≈ 0.
        let (f, l) = (s.first.unwrap(), s.last.unwrap());
        let balance = l.h_t - f.h_t + s.e_d - s.e_g;
        assert!(
            (balance - s.residual_sum).abs() < 1e-6 * f.h_t,
            "{balance} {}",
            s.residual_sum
        );
        assert!(s.e_d > 0.0);
        let text = s.render(None);
        assert!(text.starts_with("verdict: comes to rest"), "{text}");
        assert!(text.contains("ΣE_d") && text.contains("ΣE_g") && text.contains("residual"));
    }

    /// No friction and no viscous damping: the ZOH spring's negative damping (Colgate) grows
    /// the oscillation without bound.
    #[test]
    fn no_damping_grows() {
        let s = summary_of(&region(0.0, 0.0));
        assert!(
            matches!(
                s.verdict(),
                Some(Verdict::Growing | Verdict::Diverged { .. })
            ),
            "{:?}",
            s.verdict()
        );
    }

    /// Counts that toggle between two neighbours for ever are chatter, not rest; over more
    /// counts without growth, persistent. Synthetic rows over a 100-period scene, whose
    /// judged window is its last quarter, periods 76..=100 (45 natural periods of 2π√100 are
    /// longer than the run).
    #[test]
    fn toggling_counts_are_chatter_and_wider_swings_persistent() {
        let sc = scene(
            &REGION
                .replace("BETA", "1.0")
                .replace("SIGMA", "1.0")
                .replace("4000", "100"),
        );
        let run = |xi: fn(u64) -> f64| {
            let mut s = SceneSummary::new(&sc);
            for period in 0..=100 {
                s.add(&Row {
                    period,
                    xi: xi(period),
                    xidot: 0.0,
                    phi_a: 0.0,
                    h_t: 1.0,
                    e_d: 0.0,
                    e_g: 0.0,
                    residual: 0.0,
                });
            }
            s.verdict()
        };
        assert_eq!(s_window(&sc), 76);
        let two = |p: u64| if p.is_multiple_of(2) { 0.5 } else { -0.5 };
        assert_eq!(run(two), Some(Verdict::Chatter { changes: 24 }));
        let three = |p: u64| [0.5, 1.5, -0.5][(p % 3) as usize];
        assert_eq!(run(three), Some(Verdict::Persistent { counts: (-1, 1) }));
        assert_eq!(run(|_| 2.5), Some(Verdict::Rests { count: 2 }));
    }

    fn s_window(sc: &Scene) -> u64 {
        SceneSummary::new(sc).window_from
    }
}
