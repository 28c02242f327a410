//! "How stiff can my device go": `hostctl analyze` without `--stiffness` (issue 47 item 3). The
//! device's limits and the stiffest wall they predict, spring only and with the best damper,
//! capped by the quiet ceiling.
//!
//! Units: SI, in the device's own units only: K in N/m and B in N·s/m on a linear device,
//! N·m/rad and N·m·s/rad on a rotary one ([`Units`]); v in m/s (rad/s).
//!
//! The spring-only wall: the exact sampled linear limit with b alone (Gil–Avello–Rubio) is far
//! below what a real device holds, since Coulomb friction is what brings a spring to rest; the
//! prediction is the describing-function limit of Sec. VII-D with the exact sampled linear
//! boundary, Coulomb friction counted as its describing-function damping b + 4c/(πv) at the
//! velocity v (`hostctl tune`'s *expected* limit, at tune's default v = 5 ticks per period
//! unless `--velocity` is given), capped by the quiet ceiling 2c/Δ
//! (`stiffwall_core::rest::quiet_ceiling`): above it no count holds the wall's force KΔ/2 and
//! the wall chatters. The worst-case limit (12) (or (19) with a delay) and region A are given
//! beside it. The damped wall: the best B of [`crate::damping::search`] (exact linear K_max(B),
//! b and B only), capped by the same ceiling; with `--damping B`, also the wall at that B.
//!
//! Invariants: the parameters are validated by core before anything is computed (the stiffness
//! field of the [`PhysicalParams`] given is ignored); every prediction is > 0 or reported as 0
//! with the reason; a capped figure is never above the quiet ceiling.

use crate::damping::{self, FrontierPoint, FRONTIER_B_MAX_M_PER_T};
use crate::frontier::Units;
use serde::Serialize;
use std::fmt::Write as _;
use stiffwall_core::{criteria, limits, ParamError, PhysicalParams};
use stiffwall_sim::scene::field_bounds::VELOCITY;

/// The velocity of the describing-function prediction when none is given: `hostctl tune`'s
/// default maximum velocity, in encoder ticks per sampling period.
pub const DEFAULT_XIDOT: f64 = 5.0;

/// The device as analysed, without a wall.
#[derive(Debug, Clone, Serialize)]
pub struct Device {
    /// m [kg or kg·m²].
    pub mass: f64,
    /// b [N·s/m or N·m·s/rad].
    pub viscous: f64,
    /// c [N or N·m].
    pub coulomb: f64,
    /// Δ [m or rad].
    pub resolution: f64,
    /// T [s].
    pub period_s: f64,
    /// T_D [s].
    pub delay_s: f64,
    /// Rotary device (angles, torques).
    pub rotational: bool,
}

/// The spring-only wall (B = 0).
#[derive(Debug, Clone, Serialize)]
pub struct SpringOnly {
    /// Exact sampled linear limit with b alone [K unit].
    pub k_exact_linear: f64,
    /// Region A (passive), eq. (17)–(18).
    pub k_passive: f64,
    /// Worst-case limit at v: (12), or (19) with a harmonic acceleration when T_D > 0.
    pub k_guaranteed: f64,
    /// Describing-function limit at v: exact sampled linear with b + 4c/(πv).
    pub k_describing: f64,
    /// The prediction: min(`k_describing`, quiet ceiling).
    pub k_predicted: f64,
    /// Whether the quiet ceiling binds.
    pub capped: bool,
}

/// A damped wall: the exact linear K_max at B, capped by the quiet ceiling.
#[derive(Debug, Clone, Serialize)]
pub struct Damped {
    /// B [B unit].
    pub b: f64,
    /// Exact linear K_max(B) [K unit].
    pub k_max: f64,
    /// The prediction: min(`k_max`, quiet ceiling).
    pub k_predicted: f64,
    /// Whether the quiet ceiling binds (K_max(B) above it is not reachable at rest).
    pub capped: bool,
    /// When capped: the least B whose K_max reaches the quiet ceiling (a larger B up to `b`
    /// buys no stiffness at rest); null otherwise.
    pub b_least_at_ceiling: Option<f64>,
}

/// The `--json` output of `analyze` without `--stiffness`.
#[derive(Debug, Clone, Serialize)]
pub struct Stiffest {
    /// Preset name, if any.
    pub device: Option<String>,
    /// The device.
    pub params: Device,
    /// Units of K and B.
    pub units: Units,
    /// v of the describing-function and worst-case limits [m/s or rad/s].
    pub velocity: f64,
    /// v in ticks per period.
    pub xidot: f64,
    /// Whether v is tune's default ([`DEFAULT_XIDOT`]) rather than `--velocity`.
    pub velocity_default: bool,
    /// The quiet ceiling 2c/Δ [K unit].
    pub quiet_ceiling: f64,
    /// The spring alone.
    pub spring_only: SpringOnly,
    /// The best damper ([`damping::search`]).
    pub best_damper: Damped,
    /// The user's `--damping B`, if given.
    pub at_damping: Option<Damped>,
    /// The stiffest predicted wall: the best damper's when it is stiffer than the spring
    /// alone (at the least B reaching the quiet ceiling when that caps it), else the spring's.
    pub predicted: Damped,
    /// K_max(B) on 0 ..= 4·m/T, up to and including its first 0.
    pub frontier: Vec<FrontierPoint>,
    /// The first grid B where K_max(B) is 0.
    pub k_max_zero_from_b: Option<f64>,
}

fn damped(b: f64, k_max: f64, ceiling: f64) -> Damped {
    Damped {
        b,
        k_max,
        k_predicted: k_max.min(ceiling),
        capped: k_max > ceiling,
        b_least_at_ceiling: None,
    }
}

/// Bisection steps of [`least_b_at`] (the bracket shrinks to 2⁻⁴⁰ of one grid step).
const BISECT_STEPS: usize = 40;

/// The least B ≤ `b_max` with K_max(B) ≥ `k` [K unit], given K_max(`b_max`) ≥ `k`: the first
/// grid point of `frontier` reaching it, bisected against the grid point before.
fn least_b_at(
    p: &PhysicalParams,
    frontier: &[FrontierPoint],
    b_max: f64,
    k: f64,
) -> Result<f64, ParamError> {
    let i = frontier
        .iter()
        .position(|f| f.b <= b_max && f.k_max >= k)
        .unwrap_or(frontier.len());
    let mut hi = frontier.get(i).map_or(b_max, |f| f.b);
    let mut lo = if i == 0 {
        return Ok(hi);
    } else {
        frontier[i - 1].b
    };
    for _ in 0..BISECT_STEPS {
        let mid = 0.5 * (lo + hi);
        if criteria::k_max_exact_linear(p, mid)? >= k {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Ok(hi)
}

/// The limits of `p` (its stiffness ignored) at `velocity` (else [`DEFAULT_XIDOT`] ticks per
/// period), and at `damping` when given.
///
/// # Errors
/// A parameter, the velocity or B out of core's range.
pub fn stiffest(
    device: Option<String>,
    p: &PhysicalParams,
    velocity: Option<f64>,
    damping: Option<f64>,
) -> Result<Stiffest, ParamError> {
    let p = p.with_stiffness(1.0).validate()?;
    let v = match velocity {
        Some(v) => VELOCITY.check("velocity", v, p.rotational)?,
        None => p.velocity_from_xidot(DEFAULT_XIDOT),
    };
    let ceiling = stiffwall_core::rest::quiet_ceiling(p.coulomb, 0.0, p.resolution);
    let k_guaranteed = if p.delay_s > 0.0 {
        limits::k_max_delayed_harmonic(&p, v)?
    } else {
        limits::k_max_at_velocity(&p, v)?
    };
    // At v → 0 the describing-function damping 4c/(πv) grows without bound, and so does the
    // limit: the quiet ceiling binds.
    let k_describing = if v > 0.0 {
        criteria::k_max_gil_avello_rubio(&PhysicalParams {
            viscous: p.viscous + 4.0 * p.coulomb / (std::f64::consts::PI * v),
            ..p
        })?
    } else {
        f64::INFINITY
    };
    let spring_only = SpringOnly {
        k_exact_linear: criteria::k_max_gil_avello_rubio(&p)?,
        k_passive: limits::k_max_passive(&p)?,
        k_guaranteed,
        k_describing,
        k_predicted: k_describing.min(ceiling),
        capped: k_describing > ceiling,
    };
    let s = damping::search(&p, damping)?;
    let mut best_damper = damped(s.b_opt, s.k_max_opt, ceiling);
    if best_damper.capped {
        best_damper.b_least_at_ceiling = Some(least_b_at(&p, &s.frontier, s.b_opt, ceiling)?);
    }
    let at_damping = damping
        .map(|b| criteria::k_max_exact_linear(&p, b).map(|k| damped(b, k, ceiling)))
        .transpose()?;
    let predicted = match best_damper.b_least_at_ceiling {
        _ if best_damper.k_predicted <= spring_only.k_predicted => {
            damped(0.0, k_describing, ceiling)
        }
        Some(b) => Damped {
            b,
            k_max: ceiling,
            k_predicted: ceiling,
            capped: true,
            b_least_at_ceiling: Some(b),
        },
        None => best_damper.clone(),
    };
    Ok(Stiffest {
        device,
        params: Device {
            mass: p.mass,
            viscous: p.viscous,
            coulomb: p.coulomb,
            resolution: p.resolution,
            period_s: p.period_s,
            delay_s: p.delay_s,
            rotational: p.rotational,
        },
        units: Units::of(p.rotational),
        velocity: v,
        xidot: p.xidot_from_velocity(v),
        velocity_default: velocity.is_none(),
        quiet_ceiling: ceiling,
        spring_only,
        best_damper,
        at_damping,
        predicted,
        frontier: s.frontier,
        k_max_zero_from_b: s.zero_from_b,
    })
}

/// The text of `analyze` without `--stiffness`.
#[must_use]
pub fn render(r: &Stiffest) -> String {
    let (u, p) = (r.units, &r.params);
    let (m_u, c_u, x_u) = if p.rotational {
        ("kg·m²", "N·m", "rad")
    } else {
        ("kg", "N", "m")
    };
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Device: {} ({} device: K in {}, B in {})",
        r.device.as_deref().unwrap_or("(from flags)"),
        if p.rotational { "rotary" } else { "linear" },
        u.k,
        u.b
    );
    let _ = writeln!(
        s,
        "  m = {:.4e} {m_u}, b = {:.4e} {}, c = {:.4e} {c_u}, Δ = {:.4e} {x_u}, T = {:.4e} s, \
         T_D = {:.4e} s",
        p.mass, p.viscous, u.b, p.coulomb, p.resolution, p.period_s, p.delay_s
    );
    let _ = writeln!(
        s,
        "\nHow stiff a wall it can hold (no --stiffness given; --stiffness K gives the report at K)"
    );
    let _ = writeln!(
        s,
        "  quiet ceiling 2c/Δ                  {:>12.4e} {}  (above it no count holds the \
         wall's force KΔ/2: the wall chatters, it never comes to rest)",
        r.quiet_ceiling, u.k
    );
    if r.quiet_ceiling <= 0.0 {
        let _ = writeln!(
            s,
            "  no Coulomb friction: no wall comes to rest (every K chatters or grows); the \
             limits below are where a wall stays bounded"
        );
    }
    render_spring(&mut s, r);
    render_damped(&mut s, r);
    let w = &r.predicted;
    let _ = writeln!(
        s,
        "\nPredicted stiffest wall at rest: K = {:.4e} {}, B = {:.4e} {}{}",
        w.k_predicted,
        u.k,
        w.b,
        u.b,
        if w.capped { " (the quiet ceiling)" } else { "" }
    );
    s
}

/// The spring-only part of [`render`].
fn render_spring(s: &mut String, r: &Stiffest) {
    let (u, w) = (r.units, &r.spring_only);
    let _ = writeln!(
        s,
        "\nSpring only (B = 0), at v = {:.4e} {} ({:.3} ticks per period{})",
        r.velocity,
        if r.params.rotational { "rad/s" } else { "m/s" },
        r.xidot,
        if r.velocity_default {
            ", tune's default; --velocity V to change"
        } else {
            ""
        }
    );
    for (what, k) in [
        ("exact sampled linear limit, b alone", w.k_exact_linear),
        ("region A (passive), eq. (17)-(18)", w.k_passive),
        (
            if r.params.delay_s > 0.0 {
                "worst case at v, eq. (19)"
            } else {
                "worst case at v, eq. (12)"
            },
            w.k_guaranteed,
        ),
        ("describing function at v (b + 4c/(πv))", w.k_describing),
    ] {
        let _ = writeln!(s, "  {what:<40} {k:>12.4e} {}", u.k);
    }
    let _ = writeln!(
        s,
        "  predicted spring-only wall: K = {:.4e} {} ({})",
        w.k_predicted,
        u.k,
        if w.capped {
            "the describing-function limit is above the quiet ceiling: capped there"
        } else {
            "the describing-function limit: Coulomb friction is what brings a spring to rest; \
             tune's expected limit"
        }
    );
}

/// The damped part of [`render`].
fn render_damped(s: &mut String, r: &Stiffest) {
    let u = r.units;
    let _ = writeln!(
        s,
        "\nSpring + damper (exact sampled linear K_max(B), b and B; B on 0 ..= \
         {FRONTIER_B_MAX_M_PER_T}·m/T, the best refined by golden section)"
    );
    let mut line = |what: &str, d: &Damped| {
        let _ = writeln!(
            s,
            "  {what}: B = {:.4e} {}, K_max = {:.4e} {}{}",
            d.b,
            u.b,
            d.k_max,
            u.k,
            if d.capped {
                format!(
                    ": {:.3} x the quiet ceiling, not reachable at rest; capped at {:.4e} {}{}",
                    d.k_max / r.quiet_ceiling,
                    d.k_predicted,
                    u.k,
                    d.b_least_at_ceiling.map_or_else(String::new, |b| format!(
                        ", which B = {b:.4e} {} already reaches",
                        u.b
                    ))
                )
            } else {
                format!(": predicted wall K = {:.4e} {}", d.k_predicted, u.k)
            }
        );
    };
    line("best B", &r.best_damper);
    if let Some(d) = &r.at_damping {
        line("your B", d);
        if d.k_predicted < r.spring_only.k_predicted {
            let _ = writeln!(
                s,
                "  (below the spring-only wall: this damper buys no stiffness)"
            );
        }
    }
    let _ = writeln!(s, "  K_max(B):");
    damping::render_frontier(s, &r.frontier, r.k_max_zero_from_b, (u.b, u.k));
}

#[cfg(test)]
mod tests;
