//! Stability regions of the (β, σ) plane and the dissipation criteria (12), (15)–(19).
//!
//! Units: everything here is dimensionless (Table I): β, σ friction ratios; ξ̇ in encoder ticks
//! per sampling period; ξ̈ in ticks per period²; τ_D in periods. Only [`velocity_limit_m_s`]
//! returns a physical value (m/s, or rad/s for rotational devices).
//!
//! Boundary conventions: the criteria are the paper's non-strict inequalities (`≥`), so a point
//! exactly on a critical line satisfies them. Region membership follows the same convention:
//! β = ½ (or β = ½ + τ_D) counts as the high-viscosity side, σ = ½ as the high-Coulomb side.
//!
//! Invariants: every input must be finite; β, σ, τ_D, ξ̇_max, ξ̈_max must be ≥ 0. `None` for a
//! velocity or acceleration bound means "unbounded". Non-finite or negative input is a
//! [`ParamError`].

use crate::params::{check_finite, check_non_negative, check_positive, ParamError, PhysicalParams};

/// A region of Fig. 3 (τ_D = 0) or Fig. 5 (τ_D > 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Region {
    /// β ≥ ½, σ ≥ ½ (τ_D = 0): passive, globally stable.
    A,
    /// β ≥ ½ (+τ_D), σ < ½: stable limit cycles below one encoder tick.
    B,
    /// β < ½ (+τ_D), σ < ½: unstable, may generate energy at all times.
    C,
    /// β < ½ (+τ_D), σ ≥ ½, below the critical line of (12)/(19): locally unstable.
    D,
    /// β < ½ (+τ_D), σ ≥ ½, on or above the critical line: locally stable, energy decreasing.
    E,
    /// τ_D > 0, β ≥ ½ + τ_D, σ ≥ ½ + ξ̈_max(τ_D² + τ_D): (19) holds at every velocity.
    F1,
    /// τ_D > 0, β ≥ ½ + τ_D, ½ ≤ σ < ½ + ξ̈_max(τ_D² + τ_D): brief energy generation at low
    /// speed, dissipation over extended motions; stable.
    F2,
}

impl Region {
    /// One-line meaning of the region (Sec. III-B and III-D).
    #[must_use]
    pub fn meaning(&self) -> &'static str {
        match self {
            Self::A => "passive, globally stable: friction dissipates all spurious energy",
            Self::B => "stable limit cycle with amplitude below one encoder tick",
            Self::C => "unstable: may generate energy at all times",
            Self::D => "locally unstable: energy may grow from this initial velocity",
            Self::E => "locally stable: energy decreases while |velocity| stays below the limit",
            Self::F1 => {
                "stable (delay): energy decreases at every velocity, given max acceleration"
            }
            Self::F2 => {
                "stable (delay): brief energy generation at low speed, dissipated over motion"
            }
        }
    }

    /// Short label, `"A"` … `"E"`, `"F1"`, `"F2"`.
    #[must_use]
    pub fn label(&self) -> &'static str {
        match self {
            Self::A => "A",
            Self::B => "B",
            Self::C => "C",
            Self::D => "D",
            Self::E => "E",
            Self::F1 => "F1",
            Self::F2 => "F2",
        }
    }

    /// Stability rank, 0 = most stable. Along the ray of growing K (Fig. 4) the rank never
    /// decreases: A/F1 (0) → B, E, F2 (1) → D (2) → C (3).
    #[must_use]
    pub fn rank(&self) -> u8 {
        match self {
            Self::A | Self::F1 => 0,
            Self::B | Self::E | Self::F2 => 1,
            Self::D => 2,
            Self::C => 3,
        }
    }

    /// Whether the paper labels the region stable (globally or locally): A, B, E, F1, F2.
    #[must_use]
    pub fn is_stable(&self) -> bool {
        !matches!(self, Self::C | Self::D)
    }
}

impl core::fmt::Display for Region {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.label())
    }
}

/// Product that is 0 when either factor is 0 (0·∞ from an overflowed factor is 0, not NaN).
fn mul0(a: f64, b: f64) -> f64 {
    if a == 0.0 || b == 0.0 {
        0.0
    } else {
        a * b
    }
}

fn check_bs(beta: f64, sigma: f64) -> Result<(), ParamError> {
    check_non_negative("beta", beta)?;
    check_non_negative("sigma", sigma)?;
    Ok(())
}

fn check_opt(name: &'static str, v: Option<f64>) -> Result<(), ParamError> {
    if let Some(v) = v {
        check_non_negative(name, v)?;
    }
    Ok(())
}

/// Left-hand side of (12) multiplied by ξ̇ (the form (51)): ξ̇(β − ½) + (σ − ½).
/// Non-negative iff the first inequality of (12) holds at velocity ξ̇ > 0.
#[must_use]
pub fn criterion_12_margin(beta: f64, sigma: f64, xidot: f64) -> f64 {
    xidot * (beta - 0.5) + (sigma - 0.5)
}

/// Dissipation criterion (12) for τ_D = 0: (β − ½) + (σ − ½)/ξ̇_max ≥ 0 and σ ≥ ½.
/// Written as (51) so that ξ̇_max = 0 is allowed; `None` means unbounded velocity (then the
/// criterion is β ≥ ½ and σ ≥ ½, region A).
///
/// # Errors
/// [`ParamError`] on non-finite or negative input.
pub fn criterion_12(beta: f64, sigma: f64, xidot_max: Option<f64>) -> Result<bool, ParamError> {
    check_bs(beta, sigma)?;
    check_opt("xidot_max", xidot_max)?;
    Ok(sigma >= 0.5
        && match xidot_max {
            None => beta >= 0.5,
            Some(v) => criterion_12_margin(beta, sigma, v) >= 0.0,
        })
}

/// Criterion (16), sampling without quantization: (β − ½) + σ/ξ̇_max ≥ 0, evaluated as
/// ξ̇_max(β − ½) + σ ≥ 0; `None` (unbounded velocity) gives Colgate's β ≥ ½ (17).
///
/// # Errors
/// [`ParamError`] on non-finite or negative input.
pub fn criterion_16(beta: f64, sigma: f64, xidot_max: Option<f64>) -> Result<bool, ParamError> {
    check_bs(beta, sigma)?;
    check_opt("xidot_max", xidot_max)?;
    Ok(match xidot_max {
        None => beta >= 0.5,
        Some(v) => v * (beta - 0.5) + sigma >= 0.0,
    })
}

/// Left-hand side of (19): σ − ½ − ξ̈(τ_D² + τ_D) + ξ̇(β − ½ − τ_D).
#[must_use]
pub fn criterion_19_margin(beta: f64, sigma: f64, tau_d: f64, xidot: f64, xiddot: f64) -> f64 {
    sigma - 0.5 - mul0(xiddot, tau_d * tau_d + tau_d) + mul0(xidot, beta - 0.5 - tau_d)
}

/// Delayed dissipation criterion (19), required at every speed |ξ̇| ≤ ξ̇_max. Since (59) is
/// linear in |ξ̇|, that means (19) at ξ̇_max **and** at ξ̇ = 0 (σ ≥ ½ + ξ̈_max(τ_D² + τ_D)); the
/// second clause is the delayed analogue of the clause σ ≥ ½ of (12), and for τ_D = 0 this
/// function equals [`criterion_12`]. `None` = unbounded; an unbounded ξ̈_max with τ_D > 0 never
/// satisfies the criterion.
///
/// # Errors
/// [`ParamError`] on non-finite or negative input.
pub fn criterion_19(
    beta: f64,
    sigma: f64,
    tau_d: f64,
    xidot_max: Option<f64>,
    xiddot_max: Option<f64>,
) -> Result<bool, ParamError> {
    check_bs(beta, sigma)?;
    check_non_negative("tau_d", tau_d)?;
    check_opt("xidot_max", xidot_max)?;
    check_opt("xiddot_max", xiddot_max)?;
    let sigma_star = match sigma_star(tau_d, xiddot_max) {
        Some(s) => s,
        None => return Ok(false),
    };
    if sigma < sigma_star {
        return Ok(false);
    }
    let beta_star = beta_star(tau_d);
    Ok(match xidot_max {
        None => beta >= beta_star,
        Some(v) => (sigma - sigma_star) + mul0(v, beta - beta_star) >= 0.0,
    })
}

/// β* = ½ + τ_D, the viscous threshold of Fig. 3 (τ_D = 0) and Fig. 5 (τ_D > 0).
#[must_use]
pub fn beta_star(tau_d: f64) -> f64 {
    0.5 + tau_d
}

/// σ* = ½ + ξ̈_max(τ_D² + τ_D), the zero-velocity end of the critical line of (19) (½ for
/// τ_D = 0); `None` when it is unbounded (τ_D > 0 with unbounded acceleration).
#[must_use]
pub fn sigma_star(tau_d: f64, xiddot_max: Option<f64>) -> Option<f64> {
    let g = tau_d * tau_d + tau_d;
    if g == 0.0 {
        return Some(0.5);
    }
    xiddot_max.map(|a| 0.5 + mul0(a, g))
}

/// Region of Fig. 3 for τ_D = 0 (Sec. III-B), with the critical line of (12) drawn for
/// ξ̇_max (`None` = unbounded velocity, which leaves no region E).
///
/// # Errors
/// [`ParamError`] on non-finite or negative input.
pub fn classify(beta: f64, sigma: f64, xidot_max: Option<f64>) -> Result<Region, ParamError> {
    classify_delayed(beta, sigma, 0.0, xidot_max, Some(0.0))
}

/// Region of Fig. 5 for τ_D > 0 (Sec. III-D); for τ_D = 0 identical to [`classify`] (A–E).
///
/// Our reading of Fig. 5 (the figure is not in the text), with β* = ½ + τ_D and
/// σ* = ½ + ξ̈_max(τ_D² + τ_D):
/// - F1: β ≥ β*, σ ≥ σ* ((19) holds at every speed);
/// - F2: β ≥ β*, ½ ≤ σ < σ* (fails only at low speed);
/// - B: β ≥ β*, σ < ½; C: β < β*, σ < ½ (the DF analysis: (70) has limit cycles iff σ < ½,
///   and (72) needs β ≤ τ_L = β* for large unstable ones);
/// - E: β < β*, σ ≥ ½ and (19) holds at ξ̇_max (so σ ≥ σ* + ξ̇_max(β* − β));
/// - D: β < β*, σ ≥ ½ otherwise.
///
/// # Errors
/// [`ParamError`] on non-finite or negative input.
pub fn classify_delayed(
    beta: f64,
    sigma: f64,
    tau_d: f64,
    xidot_max: Option<f64>,
    xiddot_max: Option<f64>,
) -> Result<Region, ParamError> {
    check_bs(beta, sigma)?;
    check_non_negative("tau_d", tau_d)?;
    check_opt("xidot_max", xidot_max)?;
    check_opt("xiddot_max", xiddot_max)?;
    let delayed = tau_d > 0.0;
    let high_beta = beta >= beta_star(tau_d);
    if sigma < 0.5 {
        return Ok(if high_beta { Region::B } else { Region::C });
    }
    if high_beta {
        if !delayed {
            return Ok(Region::A);
        }
        return Ok(match sigma_star(tau_d, xiddot_max) {
            Some(s) if sigma >= s => Region::F1,
            _ => Region::F2,
        });
    }
    if criterion_19(beta, sigma, tau_d, xidot_max, xiddot_max)? {
        Ok(Region::E)
    } else {
        Ok(Region::D)
    }
}

/// Velocity limit (15): the largest |ξ̇| for which (12) holds, ξ̇_max = (σ − ½)/(½ − β).
/// `None` when unbounded (β ≥ ½, σ ≥ ½); `Some(0.0)` when no velocity satisfies (12) (σ < ½).
///
/// # Errors
/// [`ParamError`] on non-finite or negative input.
pub fn velocity_limit(beta: f64, sigma: f64) -> Result<Option<f64>, ParamError> {
    velocity_limit_delayed(beta, sigma, 0.0, 0.0)
}

/// Delayed analogue of (15) from (19): ξ̇_max = (σ − σ*)/(½ + τ_D − β) with
/// σ* = ½ + ξ̈_max(τ_D² + τ_D). `None` when unbounded, `Some(0.0)` when σ < σ*.
///
/// # Errors
/// [`ParamError`] on non-finite or negative input.
pub fn velocity_limit_delayed(
    beta: f64,
    sigma: f64,
    tau_d: f64,
    xiddot_max: f64,
) -> Result<Option<f64>, ParamError> {
    check_bs(beta, sigma)?;
    check_non_negative("tau_d", tau_d)?;
    check_non_negative("xiddot_max", xiddot_max)?;
    let s = sigma - sigma_star(tau_d, Some(xiddot_max)).unwrap_or(f64::INFINITY);
    let beta_star = beta_star(tau_d);
    let d = beta_star - beta;
    Ok(if s < 0.0 {
        Some(0.0)
    } else if d <= 0.0 {
        None
    } else {
        // Lower by ulps until the criterion, evaluated as in `criterion_19`, holds at it.
        Some(settle_down(s / d, |v| s + mul0(v, beta - beta_star) >= 0.0))
    })
}

/// Lowers a non-negative `v` by ulps (at most 64) until `holds(v)`.
fn settle_down(mut v: f64, holds: impl Fn(f64) -> bool) -> f64 {
    for _ in 0..64 {
        if holds(v) || v <= 0.0 {
            return v;
        }
        v = v.next_down();
    }
    v
}

/// Delayed velocity limit when the acceleration bound is that of a harmonic motion at the
/// wall's natural frequency, ξ̈_max = ξ̇_max/√μ (dimensionless ω_n = 1/√μ, from (10)):
/// ξ̇_max = (σ − ½)/(½ + τ_D − β + (τ_D² + τ_D)/√μ). Equals (15) for τ_D = 0.
///
/// # Errors
/// [`ParamError`] on non-finite or out-of-range input (μ must be > 0).
pub fn velocity_limit_harmonic(
    mu: f64,
    beta: f64,
    sigma: f64,
    tau_d: f64,
) -> Result<Option<f64>, ParamError> {
    check_positive("mu", mu)?;
    check_bs(beta, sigma)?;
    check_non_negative("tau_d", tau_d)?;
    let s = sigma - 0.5;
    let d = 0.5 + tau_d - beta + (tau_d * tau_d + tau_d) / libm::sqrt(mu);
    Ok(if s < 0.0 {
        Some(0.0)
    } else if d <= 0.0 {
        None
    } else {
        Some(s / d)
    })
}

/// Physical velocity limit (15): ẋ_max = (2c − KΔ)/(KT − 2b), in m/s (rad/s when rotational);
/// with delay, the delayed limit of [`velocity_limit_harmonic`] converted by ẋ = ξ̇Δ/T.
/// `None` when unbounded, `Some(0.0)` when no velocity satisfies the criterion.
///
/// # Errors
/// [`ParamError`] when a parameter is out of range.
pub fn velocity_limit_m_s(p: &PhysicalParams) -> Result<Option<f64>, ParamError> {
    let d = p.to_dimensionless()?;
    Ok(velocity_limit_harmonic(d.mu, d.beta, d.sigma, d.tau_d)?.map(|x| p.velocity_from_xidot(x)))
}

/// A rectangle of the (β, σ) plane, the visible part of a figure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Window {
    /// Left edge (β).
    pub beta_min: f64,
    /// Right edge (β), > `beta_min`.
    pub beta_max: f64,
    /// Bottom edge (σ).
    pub sigma_min: f64,
    /// Top edge (σ), > `sigma_min`.
    pub sigma_max: f64,
}

/// A line of Fig. 3 / Fig. 5 that separates regions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Boundary {
    /// β = β* = ½ + τ_D: B | C below σ = ½, A (F1, F2) | D, E above.
    BetaStar,
    /// σ = ½: C | D and B | A (F2).
    SigmaHalf,
    /// σ = σ*, β ≥ β*: F2 | F1 (τ_D > 0 only).
    SigmaStar,
    /// The critical line of (12)/(19), σ = σ* + ξ̇_max(β* − β) for β ≤ β*: D | E.
    Critical,
}

impl Boundary {
    /// Short description, e.g. for a legend.
    #[must_use]
    pub fn label(&self) -> &'static str {
        match self {
            Self::BetaStar => "beta = 1/2 + tau_D",
            Self::SigmaHalf => "sigma = 1/2",
            Self::SigmaStar => "sigma = sigma* (F1 | F2)",
            Self::Critical => "critical line (12)/(19)",
        }
    }
}

/// A boundary clipped to a [`Window`]: the segment from `from` to `to`, points (β, σ).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// Which line this is.
    pub boundary: Boundary,
    /// One end (β, σ).
    pub from: (f64, f64),
    /// Other end (β, σ).
    pub to: (f64, f64),
}

/// At most four boundaries, see [`boundaries`]. No allocation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Boundaries {
    segments: [Segment; 4],
    len: usize,
}

impl Boundaries {
    /// The visible segments.
    #[must_use]
    pub fn as_slice(&self) -> &[Segment] {
        &self.segments[..self.len]
    }

    /// The segment of one boundary, if visible.
    #[must_use]
    pub fn get(&self, boundary: Boundary) -> Option<Segment> {
        self.as_slice()
            .iter()
            .copied()
            .find(|s| s.boundary == boundary)
    }
}

/// A convex polygon of at most eight vertices (β, σ), counter-clockwise. No allocation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Polygon {
    vertices: [(f64, f64); 8],
    len: usize,
}

impl Polygon {
    /// The vertices; empty (or fewer than three) when the region is not visible.
    #[must_use]
    pub fn vertices(&self) -> &[(f64, f64)] {
        &self.vertices[..self.len]
    }

    /// Whether the polygon has no area.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len < 3
    }

    /// Keeps the part with a·β + b·σ ≤ c (Sutherland–Hodgman, one edge).
    fn clip(&self, (a, b, c): (f64, f64, f64)) -> Self {
        let mut out = Self {
            vertices: [(0.0, 0.0); 8],
            len: 0,
        };
        let inside = |p: (f64, f64)| a * p.0 + b * p.1 <= c;
        let mut push = |p: (f64, f64)| {
            if out.len < out.vertices.len() {
                out.vertices[out.len] = p;
                out.len += 1;
            }
        };
        for i in 0..self.len {
            let p = self.vertices[i];
            let q = self.vertices[(i + 1) % self.len];
            let (ip, iq) = (inside(p), inside(q));
            if ip {
                push(p);
            }
            if ip != iq {
                let fp = a * p.0 + b * p.1 - c;
                let fq = a * q.0 + b * q.1 - c;
                let t = fp / (fp - fq);
                push((p.0 + t * (q.0 - p.0), p.1 + t * (q.1 - p.1)));
            }
        }
        out
    }
}

/// The lines of Fig. 3 (τ_D = 0) or Fig. 5 (τ_D > 0) for the bounds ξ̇_max, ξ̈_max (`None` =
/// unbounded, as in [`classify_delayed`]), clipped to `window`. These are exactly the
/// boundaries [`classify_delayed`] uses: β* = [`beta_star`], σ = ½, σ* = [`sigma_star`] and the
/// critical line σ = σ* + ξ̇_max(β* − β) of (12)/(19). A line that misses the window, or that
/// does not exist for these bounds (no critical line for unbounded velocity, no σ* line
/// without delay), is left out.
///
/// # Errors
/// [`ParamError`] on negative or non-finite input, or a window that is not finite.
pub fn boundaries(
    tau_d: f64,
    xidot_max: Option<f64>,
    xiddot_max: Option<f64>,
    window: &Window,
) -> Result<Boundaries, ParamError> {
    check_plane(tau_d, xidot_max, xiddot_max, window)?;
    let w = window;
    let bs = beta_star(tau_d);
    let ss = sigma_star(tau_d, xiddot_max);
    let none = Segment {
        boundary: Boundary::BetaStar,
        from: (0.0, 0.0),
        to: (0.0, 0.0),
    };
    let mut out = Boundaries {
        segments: [none; 4],
        len: 0,
    };
    let mut add = |boundary, from, to| {
        if let Some((from, to)) = clip_segment(from, to, w) {
            out.segments[out.len] = Segment { boundary, from, to };
            out.len += 1;
        }
    };
    add(Boundary::BetaStar, (bs, w.sigma_min), (bs, w.sigma_max));
    add(Boundary::SigmaHalf, (w.beta_min, 0.5), (w.beta_max, 0.5));
    if let Some(ss) = ss {
        if tau_d > 0.0 && ss > 0.5 {
            add(Boundary::SigmaStar, (bs, ss), (w.beta_max.max(bs), ss));
        }
        if let Some(v) = xidot_max {
            let b0 = w.beta_min.min(bs);
            add(Boundary::Critical, (b0, ss + v * (bs - b0)), (bs, ss));
        }
    }
    Ok(out)
}

/// The part of `window` where [`classify_delayed`] returns `region` for these bounds, as a
/// convex polygon (empty when the region does not occur, e.g. A for τ_D > 0, F1/F2 for
/// τ_D = 0, E for unbounded velocity). Points on a shared edge belong to both polygons.
///
/// # Errors
/// [`ParamError`] on negative or non-finite input, or a window that is not finite.
pub fn region_polygon(
    region: Region,
    tau_d: f64,
    xidot_max: Option<f64>,
    xiddot_max: Option<f64>,
    window: &Window,
) -> Result<Polygon, ParamError> {
    check_plane(tau_d, xidot_max, xiddot_max, window)?;
    let w = window;
    let bs = beta_star(tau_d);
    let ss = sigma_star(tau_d, xiddot_max);
    let delayed = tau_d > 0.0;
    // Half-planes a·β + b·σ ≤ c.
    let low_beta = (1.0, 0.0, bs);
    let high_beta = (-1.0, 0.0, -bs);
    let low_sigma = (0.0, 1.0, 0.5);
    let high_sigma = (0.0, -1.0, -0.5);
    // The critical line σ + vβ = σ* + vβ*; `None` when there is no region E.
    let critical = match (xidot_max, ss) {
        (Some(v), Some(s)) => Some((v, s + v * bs)),
        _ => None,
    };
    let empty = Polygon {
        vertices: [(0.0, 0.0); 8],
        len: 0,
    };
    let mut poly = Polygon {
        vertices: [
            (w.beta_min, w.sigma_min),
            (w.beta_max, w.sigma_min),
            (w.beta_max, w.sigma_max),
            (w.beta_min, w.sigma_max),
            (0.0, 0.0),
            (0.0, 0.0),
            (0.0, 0.0),
            (0.0, 0.0),
        ],
        len: 4,
    };
    let half_planes: [Option<(f64, f64, f64)>; 3] = match region {
        Region::A if !delayed => [Some(high_beta), Some(high_sigma), None],
        Region::B => [Some(high_beta), Some(low_sigma), None],
        Region::C => [Some(low_beta), Some(low_sigma), None],
        Region::D => [
            Some(low_beta),
            Some(high_sigma),
            critical.map(|(v, c)| (v, 1.0, c)),
        ],
        Region::E => match critical {
            Some((v, c)) => [Some(low_beta), Some(high_sigma), Some((-v, -1.0, -c))],
            None => return Ok(empty),
        },
        Region::F1 if delayed => match ss {
            Some(s) => [Some(high_beta), Some((0.0, -1.0, -s)), None],
            None => return Ok(empty),
        },
        Region::F2 if delayed => [Some(high_beta), Some(high_sigma), ss.map(|s| (0.0, 1.0, s))],
        _ => return Ok(empty),
    };
    for h in half_planes.into_iter().flatten() {
        poly = poly.clip(h);
    }
    Ok(if poly_area(&poly) > 0.0 { poly } else { empty })
}

fn check_plane(
    tau_d: f64,
    xidot_max: Option<f64>,
    xiddot_max: Option<f64>,
    w: &Window,
) -> Result<(), ParamError> {
    check_non_negative("tau_d", tau_d)?;
    check_opt("xidot_max", xidot_max)?;
    check_opt("xiddot_max", xiddot_max)?;
    check_finite("beta_min", w.beta_min)?;
    check_finite("beta_max", w.beta_max)?;
    check_finite("sigma_min", w.sigma_min)?;
    check_finite("sigma_max", w.sigma_max)?;
    Ok(())
}

fn poly_area(p: &Polygon) -> f64 {
    let v = p.vertices();
    let mut a = 0.0;
    for i in 0..v.len() {
        let (x0, y0) = v[i];
        let (x1, y1) = v[(i + 1) % v.len()];
        a += x0 * y1 - x1 * y0;
    }
    0.5 * a
}

/// Clips the segment p–q to the window (Liang–Barsky); `None` when it misses it or is a point.
fn clip_segment(p: (f64, f64), q: (f64, f64), w: &Window) -> Option<((f64, f64), (f64, f64))> {
    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
    let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
    for (den, num) in [
        (-dx, p.0 - w.beta_min),
        (dx, w.beta_max - p.0),
        (-dy, p.1 - w.sigma_min),
        (dy, w.sigma_max - p.1),
    ] {
        if den == 0.0 {
            if num < 0.0 {
                return None;
            }
        } else {
            let t = num / den;
            if den < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    if t0 >= t1 || t0.is_nan() || t1.is_nan() {
        return None;
    }
    let at = |t: f64| (p.0 + t * dx, p.1 + t * dy);
    Some((at(t0), at(t1)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fig3_regions() {
        assert_eq!(classify(0.6, 0.6, None).unwrap(), Region::A);
        assert_eq!(classify(0.6, 0.4, Some(3.0)).unwrap(), Region::B);
        assert_eq!(classify(0.4, 0.4, Some(3.0)).unwrap(), Region::C);
        // critical line through (1/2, 1/2) with slope -xidot = -2: sigma = 1/2 + 2(1/2 - beta)
        assert_eq!(classify(0.25, 0.9, Some(2.0)).unwrap(), Region::D);
        assert_eq!(classify(0.25, 1.0, Some(2.0)).unwrap(), Region::E);
        assert_eq!(classify(0.25, 1.1, Some(2.0)).unwrap(), Region::E);
        assert_eq!(classify(0.25, 1.1, None).unwrap(), Region::D);
    }

    #[test]
    fn fig5_regions() {
        let (t, a) = (1.0, 0.1); // beta* = 1.5, sigma* = 0.5 + 0.1*2 = 0.7
        let c = |b, s, v| classify_delayed(b, s, t, v, Some(a)).unwrap();
        assert_eq!(c(1.6, 0.8, None), Region::F1);
        assert_eq!(c(1.6, 0.6, None), Region::F2);
        assert_eq!(c(1.6, 0.4, None), Region::B);
        assert_eq!(c(1.0, 0.4, Some(1.0)), Region::C);
        assert_eq!(c(1.0, 0.6, Some(1.0)), Region::D);
        assert_eq!(c(1.0, 1.3, Some(1.0)), Region::E); // 0.7 + 1*(0.5) = 1.2
        assert_eq!(c(1.0, 1.1, Some(1.0)), Region::D);
    }

    #[test]
    fn velocity_limit_15() {
        assert_eq!(velocity_limit(0.6, 0.7).unwrap(), None);
        assert_eq!(velocity_limit(0.6, 0.4).unwrap(), Some(0.0));
        let v = velocity_limit(0.25, 1.0).unwrap().unwrap();
        assert!((v - 2.0).abs() < 1e-12);
        assert!(criterion_12(0.25, 1.0, Some(v)).unwrap());
        assert!(!criterion_12(0.25, 1.0, Some(v * (1.0 + 1e-9))).unwrap());
    }

    #[test]
    fn non_finite_is_error() {
        assert!(classify(f64::NAN, 1.0, None).is_err());
        assert!(classify(0.1, 1.0, Some(f64::INFINITY)).is_err());
        assert!(criterion_19(0.1, 1.0, -1.0, None, None).is_err());
    }

    /// Every polygon's interior points classify as its region, and the polygons tile the
    /// window (their areas add up to the window's).
    #[test]
    fn polygons_match_classify() {
        let w = Window {
            beta_min: 0.0,
            beta_max: 3.0,
            sigma_min: 0.0,
            sigma_max: 4.0,
        };
        let all = [
            Region::A,
            Region::B,
            Region::C,
            Region::D,
            Region::E,
            Region::F1,
            Region::F2,
        ];
        for (t, v, a) in [
            (0.0, Some(2.0), Some(0.0)),
            (0.0, None, Some(0.0)),
            (1.0, Some(1.0), Some(0.1)),
            (0.3, Some(4.0), Some(0.5)),
            (0.3, Some(4.0), None),
        ] {
            let mut total = 0.0;
            for r in all {
                let p = region_polygon(r, t, v, a, &w).unwrap();
                total += poly_area(&p);
                if p.is_empty() {
                    continue;
                }
                // Centroid of the vertices: inside a convex polygon.
                let n = p.vertices().len() as f64;
                let (cb, cs) = p
                    .vertices()
                    .iter()
                    .fold((0.0, 0.0), |(x, y), q| (x + q.0 / n, y + q.1 / n));
                assert_eq!(
                    classify_delayed(cb, cs, t, v, a).unwrap(),
                    r,
                    "{t} {v:?} {a:?}"
                );
            }
            assert!((total - 12.0).abs() < 1e-9, "{t} {v:?} {a:?}: {total}");
        }
    }

    #[test]
    fn boundaries_are_the_classify_thresholds() {
        let w = Window {
            beta_min: -0.5,
            beta_max: 3.0,
            sigma_min: 0.0,
            sigma_max: 2.0,
        };
        // Fig. 3 with ξ̇_max = 2: critical line σ = ½ + 2(½ − β), leaving the window at σ = 2.
        let b = boundaries(0.0, Some(2.0), Some(0.0), &w).unwrap();
        assert_eq!(b.as_slice().len(), 3);
        let c = b.get(Boundary::Critical).unwrap();
        assert!((c.from.0 + 0.25).abs() < 1e-12 && (c.from.1 - 2.0).abs() < 1e-12);
        assert_eq!(c.to, (0.5, 0.5));
        assert!(b.get(Boundary::SigmaStar).is_none());
        // Fig. 5: β* = 1.5, σ* = 0.7.
        let b = boundaries(1.0, Some(1.0), Some(0.1), &w).unwrap();
        assert_eq!(b.get(Boundary::BetaStar).unwrap().from, (1.5, 0.0));
        let s = b.get(Boundary::SigmaStar).unwrap();
        assert!((s.from.1 - 0.7).abs() < 1e-12 && s.to.0 == 3.0);
        assert!(boundaries(0.0, None, Some(0.0), &w)
            .unwrap()
            .get(Boundary::Critical)
            .is_none());
        assert!(boundaries(f64::NAN, None, None, &w).is_err());
    }
}
