//! The (B, K) plane of one device as data: virtual damping B on x, wall stiffness K on y, with
//! core's predicted exact linear boundary K_max(B) (`stiffwall_core::criteria::k_max_exact_linear`)
//! and the frontier figure's content ([`Frontier`]), shared by `hostctl map --k-b`, `hostctl
//! analyze --damping B --plot` and `hostctl tune --plot` (which draw it).
//!
//! Units: B in N·s/m and K in N/m for a linear device, N·m·s/rad and N·m/rad for a rotational
//! one ([`Units`]).
//!
//! Invariants: the boundary is computed by core (here by [`boundary`], or by the caller), never
//! restated; [`Frontier::ranges`] are positive and finite. The frontier figure's file is named
//! [`kb_path`] of the (β, σ) figure's.

use serde::Serialize;
use std::path::{Path, PathBuf};
use stiffwall_core::{criteria, PhysicalParams};

/// Number of B values of [`boundary`].
pub const BOUNDARY_POINTS: usize = 81;

/// Units of the axes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Units {
    /// Unit of K.
    pub k: &'static str,
    /// Unit of B.
    pub b: &'static str,
}

impl Units {
    /// SI units of K and B.
    #[must_use]
    pub fn of(rotational: bool) -> Self {
        if rotational {
            Self {
                k: "N·m/rad",
                b: "N·m·s/rad",
            }
        } else {
            Self {
                k: "N/m",
                b: "N·s/m",
            }
        }
    }
}

/// `<stem>-kb.<ext>` beside `path` (`dir/t.svg` → `dir/t-kb.svg`).
#[must_use]
pub fn kb_path(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .map_or_else(|| "plot".to_string(), |s| s.to_string_lossy().into_owned());
    let name = match path.extension() {
        Some(e) => format!("{stem}-kb.{}", e.to_string_lossy()),
        None => format!("{stem}-kb"),
    };
    path.with_file_name(name)
}

/// K_max(B) of `p` on [`BOUNDARY_POINTS`] B values linear in 0 ..= `b_max` [N·s/m or
/// N·m·s/rad], as (B, K_max) pairs; B values where core refuses the parameters are left out.
#[must_use]
pub fn boundary(p: &PhysicalParams, b_max: f64) -> Vec<(f64, f64)> {
    let n = BOUNDARY_POINTS - 1;
    (0..=n)
        .map(|i| b_max * i as f64 / n as f64)
        .filter_map(|b| criteria::k_max_exact_linear(p, b).ok().map(|k| (b, k)))
        .collect()
}

/// A highlighted (B, K) point with its legend text.
#[derive(Debug, Clone)]
pub struct Mark {
    /// B [N·s/m or N·m·s/rad].
    pub b: f64,
    /// K [N/m or N·m/rad].
    pub k: f64,
    /// Legend text.
    pub label: String,
}

/// The frontier figure: the predicted boundary and what was verified or chosen on it.
#[derive(Debug, Clone)]
pub struct Frontier {
    /// Caption.
    pub title: String,
    /// Units of the axes.
    pub units: Units,
    /// Predicted K_max(B), (B, K) pairs.
    pub boundary: Vec<(f64, f64)>,
    /// Legend text of the boundary.
    pub boundary_label: String,
    /// Verified points (B, largest resting K); None: none verified at that B (drawn as a
    /// cross on the B axis).
    pub verified: Vec<(f64, Option<f64>)>,
    /// The spring-only wall's K (drawn at B = 0).
    pub spring_only: Option<f64>,
    /// The best B of the boundary.
    pub best: Option<Mark>,
    /// The chosen pair or operating point (highlighted).
    pub chosen: Option<Mark>,
    /// The quiet ceiling 2·max(c, F_s)/Δ (a horizontal line): above it no wall comes to rest
    /// (the chatter band, up to the growth boundary K_max(B)). None: not drawn.
    pub quiet_ceiling: Option<f64>,
}

impl Frontier {
    /// The plotted (B, K) ranges: everything drawn, with room above for the legend.
    #[must_use]
    pub fn ranges(&self) -> (f64, f64) {
        let marks = self.best.iter().chain(self.chosen.iter());
        let bs = self.boundary.iter().map(|p| p.0);
        let bs = bs.chain(self.verified.iter().map(|v| 1.05 * v.0));
        let b_max = bs
            .chain(marks.clone().map(|m| 1.05 * m.b))
            .fold(0.0, f64::max);
        let ks = self.boundary.iter().map(|p| p.1).filter(|k| k.is_finite());
        let ks = ks.chain(self.verified.iter().filter_map(|v| v.1));
        let ks = ks.chain(self.spring_only).chain(marks.map(|m| m.k));
        let ks = ks.chain(self.quiet_ceiling.filter(|k| k.is_finite()));
        let k_max = 1.35 * ks.fold(0.0, f64::max);
        let pos = |x: f64| if x > 0.0 && x.is_finite() { x } else { 1.0 };
        (pos(b_max), pos(k_max))
    }
}

/// `x` to 4 significant digits: plain between 10⁻³ and 10⁵ (`3.722`, `2640`), else with a
/// power of ten (`3.507e6`); `n/a` for a value that is not finite.
#[must_use]
pub fn sig(x: f64) -> String {
    if !x.is_finite() {
        return "n/a".to_owned();
    }
    let a = x.abs();
    if a == 0.0 {
        "0".to_owned()
    } else if (1e-3..1e5).contains(&a) {
        let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.3e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kb_path_puts_kb_before_the_extension() {
        assert_eq!(kb_path(Path::new("d/t.svg")), PathBuf::from("d/t-kb.svg"));
        assert_eq!(kb_path(Path::new("a.b.PNG")), PathBuf::from("a.b-kb.PNG"));
        assert_eq!(kb_path(Path::new("t")), PathBuf::from("t-kb"));
    }

    #[test]
    fn ranges_cover_everything_and_stay_positive_when_all_is_zero_or_not_finite() {
        let mut f = Frontier {
            title: "t".into(),
            units: Units::of(false),
            boundary: vec![(0.0, 50.0), (3.0, f64::NAN)],
            boundary_label: "boundary".into(),
            verified: vec![(2.0, Some(900.0))],
            spring_only: Some(100.0),
            best: None,
            chosen: Some(Mark {
                b: 0.0,
                k: 100.0,
                label: "set wall".into(),
            }),
            quiet_ceiling: None,
        };
        let (b, k) = f.ranges();
        assert!(b >= 3.0 && k > 900.0, "{b} {k}");
        f.verified.clear();
        f.boundary.clear();
        f.spring_only = None;
        f.chosen = None;
        assert_eq!(f.ranges(), (1.0, 1.0));
    }
}
