//! The paper's per-interval bounds on the generated energy, (47) for τ_D = 0 and (58) for
//! τ_D > 0, checked on exact trajectories; the tight bound of `stiffwall_sim::bounds::tight`
//! must hold everywhere, (47)/(58) fail (erratum in docs/model-notes-sim.md).

use std::collections::VecDeque;
use stiffwall_sim::bounds::{generated, paper_47, paper_58, tight};
use stiffwall_sim::math::floor_fast;
use stiffwall_sim::plant::{advance, Body, Motion};

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        // xorshift64*
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

#[derive(Debug, Clone, Copy)]
struct Check {
    xi_h: f64,
    xi_l: f64,
    xi_1: f64,
    e_g: f64,
    tight: f64,
    paper: f64,
}

/// Simulates μξ̈ + βξ̇ + σ sgn ξ̇ = φ_A exactly with sampling at integers and force switches at
/// h + τ_D, and evaluates E_g(l, τ₁) at one random τ₁ ∈ ]l, l + 1[ of every interval.
fn trajectory(
    rng: &mut Rng,
    mu: f64,
    beta: f64,
    sigma: f64,
    tau_d: f64,
    init: Motion,
    periods: u32,
) -> Vec<Check> {
    let body = Body::new(mu, beta, sigma);
    let spring = |x: f64| -floor_fast(x) - 0.5;
    let mut st = init;
    let mut t = 0.0;
    let mut force = spring(init.x);
    let mut pending: VecDeque<(f64, f64, f64)> = VecDeque::new();
    let mut obs: Option<(f64, f64, f64, f64)> = None;
    let mut next_sample = 0u32;
    let mut out = Vec::new();
    while next_sample <= periods {
        let ts = f64::from(next_sample);
        let mut te = ts;
        if let Some(&(tp, _, _)) = pending.front() {
            te = te.min(tp);
        }
        if let Some((to, ..)) = obs {
            te = te.min(to);
        }
        advance::<false>(&body, &mut st, force, te - t);
        t = te;
        if st.x.is_nan() || st.x.abs() >= 1e6 {
            break;
        }
        if let Some((to, xi_h, xi_l, phi)) = obs {
            if to == te {
                let d = st.x - xi_l;
                let d0 = xi_l - xi_h;
                let paper = if tau_d == 0.0 {
                    paper_47(d)
                } else {
                    paper_58(d, d0)
                };
                out.push(Check {
                    xi_h,
                    xi_l,
                    xi_1: st.x,
                    e_g: generated(phi, xi_l, st.x),
                    tight: tight(d, d0),
                    paper,
                });
                obs = None;
            }
        }
        if te == ts {
            pending.push_back((ts + tau_d, st.x, spring(st.x)));
            next_sample += 1;
        }
        while let Some(&(tp, xi_h, phi)) = pending.front() {
            if tp != te {
                break;
            }
            pending.pop_front();
            force = phi;
            obs = Some((te + rng.range(1e-6, 0.999), xi_h, st.x, phi));
        }
    }
    out
}

fn run(tau_d_of: impl Fn(&mut Rng) -> f64, seed: u64) -> (usize, usize, Option<Check>, f64) {
    let mut rng = Rng(seed);
    let (mut n, mut violations, mut worst, mut worst_gap) = (0, 0, None, 0.0);
    for _ in 0..300 {
        let mu = rng.range(0.2, 200.0);
        let beta = rng.range(0.0, 1.0);
        let sigma = rng.range(0.0, 1.5);
        let tau_d = tau_d_of(&mut rng);
        let init = Motion {
            x: rng.range(-3.0, 3.0),
            v: rng.range(-10.0, 10.0),
        };
        for c in trajectory(&mut rng, mu, beta, sigma, tau_d, init, 200) {
            n += 1;
            let scale =
                1.0 + (c.xi_1 - c.xi_l).powi(2) + (c.xi_l - c.xi_h).abs() * (c.xi_1 - c.xi_l).abs();
            assert!(
                c.e_g <= c.tight + 1e-9 * scale,
                "tight bound violated: {c:?}"
            );
            if c.e_g > c.paper + 1e-9 * scale {
                violations += 1;
                if c.e_g - c.paper > worst_gap {
                    worst_gap = c.e_g - c.paper;
                    worst = Some(c);
                }
            }
        }
    }
    (n, violations, worst, worst_gap)
}

#[test]
fn tight_bound_holds_and_47_fails_without_delay() {
    let (n, violations, worst, gap) = run(|_| 0.0, 7);
    println!(
        "tau_D = 0: {n} intervals, (47) violated in {violations}, worst excess {gap} at {worst:?}"
    );
    assert!(n > 10_000);
    assert!(violations > 0, "expected counterexamples to (47)");
    // The excess over (47) is at most 1/8 (tight − (47) = ½δ(1−δ)).
    assert!(gap <= 0.125 + 1e-9);
}

#[test]
fn tight_bound_holds_and_58_fails_with_delay() {
    let (n, violations, worst, gap) = run(|r| r.range(0.0, 3.0), 11);
    println!(
        "tau_D > 0: {n} intervals, (58) violated in {violations}, worst excess {gap} at {worst:?}"
    );
    assert!(n > 10_000);
    assert!(violations > 0, "expected counterexamples to (58)");
    let (_, v_int, _, _) = run(|r| (r.range(0.0, 3.0) as u32).into(), 13);
    assert!(v_int > 0);
}

/// A concrete counterexample to (47) on an exact trajectory (documented in the model notes):
/// μ = 100, β = σ = 0, released at ξ₀ = 1 − 10⁻⁹ with ξ̇₀ = 0.5. Over the first period the spring
/// holds φ_C = −½ while the mass crosses the boundary ξ = 1 almost at once.
#[test]
fn counterexample_to_47() {
    let body = Body::new(100.0, 0.0, 0.0);
    let x0 = 1.0 - 1e-9;
    let mut m = Motion { x: x0, v: 0.5 };
    let phi = -floor_fast(x0) - 0.5;
    advance::<false>(&body, &mut m, phi, 1.0);
    let d = m.x - x0;
    let e_g = generated(phi, x0, m.x);
    assert!((d - 0.4975).abs() < 1e-9);
    assert!(
        e_g > paper_47(d) + 0.12,
        "E_g {e_g} vs (47) {}",
        paper_47(d)
    );
    assert!(e_g <= tight(d, 0.0));
}

use stiffwall_sim::exact::{storage, ExactSim, History, NoDelay};
use stiffwall_sim::Params;

/// Largest one-period increase of H_T at sample instants over `periods` periods.
fn max_increase(p: Params, v0: f64, periods: u32) -> f64 {
    let mut s = NoDelay::new(p, Motion { x: 0.0, v: v0 }, History::HoldInitial).unwrap();
    let mut prev = storage(p.mu, 0.0, v0);
    let mut worst = f64::NEG_INFINITY;
    for _ in 0..periods {
        s.step_period();
        let st = s.state();
        let h = storage(p.mu, st.x, st.v);
        worst = worst.max(h - prev);
        prev = h;
    }
    worst
}

/// Consequence of the erratum: in region A with ½ < σ < 1 the energy H_T is *not* monotone at
/// sample instants (the light band of docs/figures/fig6-tau0.png), while β ≥ ½, σ ≥ 1 (the
/// criterion that follows from the tight bound) gives monotone decay.
#[test]
fn region_a_needs_sigma_one_for_monotone_energy() {
    let p = Params {
        mu: 100.0,
        beta: 0.6,
        sigma: 0.7,
        tau_d: 0.0,
    };
    assert!(max_increase(p, 5.0, 5000) > 1e-3);
    let mut rng = Rng(99);
    for _ in 0..200 {
        let p = Params {
            mu: rng.range(0.2, 300.0),
            beta: rng.range(0.5, 3.0),
            sigma: rng.range(1.0, 2.0),
            tau_d: 0.0,
        };
        let v0 = rng.range(-30.0, 30.0);
        let inc = max_increase(p, v0, 2000);
        let scale = storage(p.mu, 0.0, v0).max(1.0);
        assert!(inc <= 1e-12 * scale, "{p:?} v0 {v0}: H_T rose by {inc}");
    }
}
