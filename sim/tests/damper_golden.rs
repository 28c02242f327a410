//! Golden trajectories of the exact solver recorded from `main` BEFORE the virtual damper was
//! added: with damping β_v = 0 every trajectory must stay bit-for-bit identical.
//!
//! Each case hashes (FNV-1a, 64 bit) the f64 bit patterns of the state (ξ, ξ̇) at every sample
//! instant and, for audited cases, of the period audit (H_T, E_d, E_g, residual). The hashes in
//! [`GOLDEN`] are the independent reference: they are main's behaviour before the change.
//! Regenerate (only if main's undamped behaviour is meant to change) with
//! `STIFFWALL_PRINT_GOLDEN=1 cargo test -p stiffwall-sim --test damper_golden -- --nocapture
//! undamped_solver_matches_main_bit_for_bit` (prints this run's table before comparing).

use stiffwall_sim::exact::{dispatch, dispatch_damped, ExactSim, History, Visitor};
use stiffwall_sim::{Effects, Motion, Params};

/// FNV-1a over 64-bit words.
#[derive(Clone, Copy)]
struct Fnv(u64);
impl Fnv {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
    fn word(&mut self, w: u64) {
        for b in w.to_le_bytes() {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
    fn f(&mut self, x: f64) {
        self.word(x.to_bits());
    }
}

/// Steps `periods` periods and hashes every sampled state (and audit when `audited`).
struct Hash {
    periods: u64,
    audited: bool,
}
impl Visitor for Hash {
    type Output = u64;
    fn visit<S: ExactSim>(self, mut s: S) -> u64 {
        let mut h = Fnv::new();
        for _ in 0..self.periods {
            s.step_period();
            let st = s.state();
            h.f(st.x);
            h.f(st.v);
            if self.audited {
                let a = s.audit();
                for x in [a.h_start, a.h_end, a.e_d, a.e_g, a.residual] {
                    h.f(x);
                }
            }
            h.word(u64::from(s.at_rest()));
        }
        h.f(s.applied_force());
        h.0
    }
}

/// One golden case.
#[derive(Debug, Clone, Copy)]
pub struct Case {
    params: Params,
    effects: Effects,
    init: Motion,
    history: History,
    audited: bool,
}

/// 128 deterministic cases spread over (μ, β, σ, τ_D, ξ̇₀, ξ₀, quantization, one-/two-sided,
/// history, audit), drawn by a fixed LCG.
fn cases() -> Vec<Case> {
    const MU: [f64; 5] = [0.5, 3.0, 20.0, 100.0, 1000.0];
    const BETA: [f64; 4] = [0.0, 0.01, 0.1, 1.5];
    const SIGMA: [f64; 4] = [0.0, 0.3, 1.0, 4.0];
    const TAU: [f64; 5] = [0.0, 0.5, 1.0, 2.25, 7.75];
    const V0: [f64; 5] = [-3.0, 0.0, 0.7, 5.0, 60.0];
    const X0: [f64; 4] = [0.0, -2.3, 0.4, 7.9];
    let mut seed: u64 = 0x5eed_da3b_e12a_0001;
    let mut pick = |n: usize| {
        seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((seed >> 33) % n as u64) as usize
    };
    (0..128)
        .map(|_| {
            let tau_d = TAU[pick(TAU.len())];
            let effects = Effects {
                quantization: pick(5) != 0,
                coulomb: true,
                viscous: true,
                delay: tau_d > 0.0 || pick(2) == 0,
                one_sided: pick(2) == 0,
            };
            Case {
                params: Params {
                    mu: MU[pick(MU.len())],
                    beta: BETA[pick(BETA.len())],
                    sigma: SIGMA[pick(SIGMA.len())],
                    tau_d,
                },
                effects,
                init: Motion {
                    x: X0[pick(X0.len())],
                    v: V0[pick(V0.len())],
                },
                history: if pick(4) == 0 {
                    History::Zero
                } else {
                    History::HoldInitial
                },
                audited: pick(2) == 0,
            }
        })
        .collect()
}

const PERIODS: u64 = 3000;

/// Hash of one case through the undamped solver API of main.
fn run(c: &Case) -> u64 {
    let vis = Hash {
        periods: PERIODS,
        audited: c.audited,
    };
    if c.audited {
        dispatch::<_, true>(c.params, c.effects, c.init, c.history, vis).unwrap()
    } else {
        dispatch::<_, false>(c.params, c.effects, c.init, c.history, vis).unwrap()
    }
}

/// The same case through the damped API with damping `beta_v`.
fn run_damped(c: &Case, beta_v: f64) -> u64 {
    let vis = Hash {
        periods: PERIODS,
        audited: c.audited,
    };
    if c.audited {
        dispatch_damped::<_, true>(c.params, c.effects, c.init, c.history, beta_v, vis).unwrap()
    } else {
        dispatch_damped::<_, false>(c.params, c.effects, c.init, c.history, beta_v, vis).unwrap()
    }
}

/// β_v = 0 through the damped API is main; β_v > 0 must change trajectories (so the
/// comparison can fail).
#[test]
fn zero_damping_is_main_and_positive_damping_is_not() {
    let cs = cases();
    let mut changed = 0;
    for (i, (c, &g)) in cs.iter().zip(GOLDEN.iter()).enumerate() {
        assert_eq!(run_damped(c, 0.0), g, "case {i}: {c:?}");
        changed += usize::from(run_damped(c, 0.5) != g);
    }
    assert!(
        changed > 64,
        "only {changed} of 128 changed with beta_v = 0.5"
    );
}

#[test]
fn undamped_solver_matches_main_bit_for_bit() {
    let cs = cases();
    if std::env::var_os("STIFFWALL_PRINT_GOLDEN").is_some() {
        for c in &cs {
            println!("    0x{:016x},", run(c));
        }
    }
    assert_eq!(cs.len(), GOLDEN.len());
    for (i, (c, &g)) in cs.iter().zip(GOLDEN.iter()).enumerate() {
        assert_eq!(run(c), g, "case {i}: {c:?}");
    }
}

/// Hashes recorded from main before the damper (see the module header).
const GOLDEN: [u64; 128] = [
    0x7eb0420e171169bd,
    0x4f33fe9782db7d0d,
    0xc0e9026d86da909c,
    0xc62f2c7b545204d9,
    0x60139b791fa774ad,
    0xa22a22dd5cd8aeb4,
    0x3bf2cb001f5c87de,
    0x59cf4733e6fcf528,
    0x09be165d637a00f1,
    0x474ae45aec8d58fd,
    0xbbbfcccdab350b9b,
    0xac550403ee31ec4c,
    0x510cd7dcf4be6a66,
    0x97c4111ed4c4601d,
    0xe2b2f4b059b9e743,
    0xc80c236a96462b64,
    0x50b4421d663afc05,
    0x4fbd5d4ca314c3d9,
    0xb84592a7d47d1663,
    0xc6becb1e95764136,
    0xc15244689b9bb4e3,
    0x3477707ac2eaec25,
    0xa621782fee6973f0,
    0x44167fd285cf6100,
    0xab8c7a3b00dc2674,
    0x895e1e3b15f17e91,
    0xe76a00c32980361e,
    0xf64f36ee1088fb2d,
    0xb7e798cab3eaeae5,
    0x8fc8a525e79630dd,
    0x399be92d648c7801,
    0xfc949baad3592881,
    0x2f1abf5bc3508a02,
    0x6c87a80e8c5795b1,
    0x5cba64b45904aa6a,
    0xe31e13678481ebb4,
    0xea206d0290332cc0,
    0xcf25f4039efcda7c,
    0x0fd6558e4b1aef8c,
    0xe164c1b7a62c867c,
    0xa2e7316be4b88a8a,
    0x694b090e5effd2c6,
    0xb355dd33836f4e0f,
    0xfc9c6e5e3fb1dde1,
    0x00cc88f294ff2274,
    0x6f928b6c8cea35eb,
    0x9556fa877c9d40ca,
    0x1c459b085ad134e1,
    0xef6df07f8e24e463,
    0x77f15ecf4cea677d,
    0x04d4087b598803cc,
    0x59bf4a3ad50486be,
    0xdbeb7750aed9f99a,
    0x0f3e735ea629fd6c,
    0xd0b7750ba96e5fc1,
    0xe7e458581739212a,
    0x4022559cdcbad159,
    0xe3e1ce4ed8982060,
    0x2730d4930221113d,
    0xfbe1210e9018bb2f,
    0xc1bd7d0a3a6a9035,
    0xf0a60e0dc757d2a8,
    0x2f5e07dbe9833259,
    0x5eee76ec6192633e,
    0x220518f833398afd,
    0x78814894312b6c12,
    0x4b08127e44d6da95,
    0x0de90b78905aea92,
    0x4644f2238f57a291,
    0x5444cbffe4475964,
    0xa448aac59ab97e0d,
    0x4f1448c9f7837b3b,
    0x2e1340393cea59f8,
    0x960e069b5a60ace7,
    0xf7cb86d4642ce7ad,
    0x97e908e318720ed7,
    0xd374aa5e16beedea,
    0xe01bf7e9b0da4c09,
    0x905ba4ac3ad31a82,
    0x5f8ad38de764ca98,
    0xa71e46d3ecdc9586,
    0x7af50176b87eac98,
    0x87b9e876afd229e9,
    0x5330d5cafabd8062,
    0x227b9ef8de78a6ac,
    0x50f27d6eb65b3861,
    0xde5879a510a5fe64,
    0xbd1340ea5fb1e4c4,
    0xac550403ee31ec4c,
    0x996a3e07d68f67b5,
    0x4ba5272ce269495d,
    0xf02b92588bc9049a,
    0x8b3c7a8d0a806b21,
    0x84ed498bc2c164d0,
    0x9454839e2acf5c1b,
    0x7b954dcb067b4ed7,
    0xa8b8ac54b80b86ab,
    0xc75df79bd9482415,
    0xce77f86d489c77b2,
    0x72404fa9e425f0d2,
    0xc05ef16ab0c804c8,
    0xe47f5d39a4818424,
    0x86973e43b0a7f6b2,
    0xece311fb1c46e9a6,
    0xfe1724b8f4dea71a,
    0x0e1570cfa91a5a24,
    0xe51df8b69c659d35,
    0x6c183dabbddfbf14,
    0x95c26ae5b48e9bd9,
    0xeedd7c744f106fdf,
    0xb9d961f1c7cf7b11,
    0x2fb286fd3f6f7b92,
    0xd47737ec800acf1a,
    0x43f555524bd66f1d,
    0xf5a9429ecfe7b39e,
    0x980895958be6890a,
    0x4363acbc5747d641,
    0xa839aa99c6295793,
    0xfecbccfd58a63993,
    0x7add172f9d148469,
    0xd9b6e6829dbcb8b4,
    0x25769ee4fb7fc2f0,
    0x80036500e12faaa9,
    0x1a6875fc705bfb61,
    0xca5fa7951d5a0532,
    0xa6e77d8d5f1594c3,
    0x28627a1f3690ad69,
    0x277948666249a056,
];
