//! SIL: the firmware servo (fixed point, supervisor) drives the simulated plant in the
//! paper's regions A, B and C (Fig. 3), μ = 100, τ_D = 0, released from rest at ξ₀ = 20.5.

use stiffwall_firmware::{Channels, Servo};
use stiffwall_proto::fault;
use stiffwall_tests::{board, config, tick, tick_offset, Plant, Point, K};

struct Run {
    /// Position per tick, m.
    x: Vec<f64>,
    /// Velocity per tick, m/s.
    v: Vec<f64>,
    /// Tick at which a fault latched, and which.
    trip: Option<(usize, u32)>,
}

fn release<P: Plant>(mut plant: P, x0_ticks: f64, ticks: usize, monitor: bool) -> Run {
    let d = f64::from(board().resolution);
    plant.set(x0_ticks * d, 0.0);
    let mut ch = Channels::new();
    let (sp, _hp) = ch.split();
    let mut servo: Servo<'_> = Servo::new(board(), &config(monitor), sp);
    let mut run = Run {
        x: Vec::new(),
        v: Vec::new(),
        trip: None,
    };
    for t in 0..ticks {
        tick(&mut servo, &mut plant, t as u32);
        run.x.push(plant.position());
        run.v.push(plant.velocity());
        if run.trip.is_none() && servo.faults() != 0 {
            run.trip = Some((t, servo.faults()));
        }
    }
    run
}

fn ticks(x: f64) -> f64 {
    x / f64::from(board().resolution)
}

fn peak(xs: &[f64]) -> f64 {
    xs.iter().fold(0.0f64, |a, &x| a.max(ticks(x).abs()))
}

/// Mechanical energy of the device + an ideal spring, J.
fn energy(p: Point, x: f64, v: f64) -> f64 {
    let (m, _, _) = p.si();
    0.5 * m * v * v + 0.5 * K * x * x
}

const A: Point = Point {
    mu: 100.0,
    beta: 1.0,
    sigma: 1.0,
};
const B: Point = Point {
    mu: 100.0,
    beta: 1.0,
    sigma: 0.2,
};
const B0: Point = Point {
    mu: 100.0,
    beta: 1.0,
    sigma: 0.0,
};
const C: Point = Point {
    mu: 100.0,
    beta: 0.1,
    sigma: 0.2,
};

#[test]
fn region_a_settles_after_release() {
    for monitor in [false, true] {
        let r = release(A.sim_plant(), 20.5, 4000, monitor);
        assert_eq!(r.trip, None, "no fault in region A");
        let tail = 3000..4000;
        assert!(
            r.v[tail.clone()].iter().all(|&v| v == 0.0),
            "at rest (stuck) at the end"
        );
        let xf = ticks(r.x[3999]);
        assert!(
            (-1.0..=1.0).contains(&xf),
            "settled at {xf} ticks, within one tick of the wall"
        );
        assert!(r.x[tail].iter().all(|&x| x == r.x[3999]));
    }
}

#[test]
fn region_a_settles_with_the_independent_euler_plant_too() {
    let r = release(A.euler_plant(), 20.5, 4000, true);
    assert_eq!(r.trip, None);
    assert!(r.v[3000..].iter().all(|&v| v == 0.0));
    assert!(ticks(r.x[3999]).abs() <= 1.0);
}

#[test]
fn region_c_oscillation_grows_without_the_monitor() {
    let r = release(C.sim_plant(), 20.5, 1500, false);
    assert_eq!(r.trip, None);
    let late = peak(&r.x[1200..]);
    assert!(
        late > 40.0,
        "region C must grow: late peak {late} ticks from 20.5"
    );
}

#[test]
fn region_c_energy_monitor_trips_and_energy_stops_growing() {
    let r = release(C.sim_plant(), 20.5, 3000, true);
    let (t_trip, faults) = r.trip.expect("the energy monitor must trip in region C");
    assert_eq!(faults & fault::ENERGY_GROWTH, fault::ENERGY_GROWTH);
    // Bounded detection: the oscillation period is 2π√μ ≈ 63 ticks; growth score 4 needs
    // 2 + 4 turning points (3 periods) once the peaks grow by ≥ 1 count per half-cycle.
    assert!(t_trip <= 400, "tripped after {t_trip} ticks");
    let e0 = energy(C, r.x[0], 0.0);
    let e_trip = energy(C, r.x[t_trip], r.v[t_trip]);
    assert!(e_trip < 3.0 * e0, "energy at trip {e_trip} vs initial {e0}");
    // After the trip the output is zero (safe mode): the device's kinetic energy never grows
    // again and it comes to rest.
    let (m, _, _) = C.si();
    let ke: Vec<f64> = r.v.iter().map(|v| 0.5 * m * v * v).collect();
    for t in t_trip + 1..ke.len() {
        assert!(
            ke[t] <= ke[t - 1] * (1.0 + 1e-12),
            "kinetic energy grew at tick {t} after trip at {t_trip}"
        );
    }
    assert_eq!(*r.v.last().unwrap(), 0.0);
    eprintln!(
        "region C: trip at tick {t_trip}, peak before trip {:.1} ticks, energy x{:.2} of initial",
        peak(&r.x[..=t_trip]),
        e_trip / e0
    );
}

#[test]
fn region_b_limit_cycle_of_about_one_tick() {
    for monitor in [false, true] {
        let r = release(B.sim_plant(), 20.5, 20_000, monitor);
        assert_eq!(
            r.trip, None,
            "the monitor must not trip on a region-B limit cycle"
        );
        let tail = &r.x[15_000..];
        let p = peak(tail);
        let moving = r.v[15_000..].iter().filter(|v| **v != 0.0).count();
        let crossings = tail
            .windows(2)
            .filter(|w| (w[0] >= 0.0) != (w[1] >= 0.0))
            .count();
        let counts: Vec<i64> = tail.iter().map(|&x| ticks(x).floor() as i64).collect();
        let (lo, hi) = (*counts.iter().min().unwrap(), *counts.iter().max().unwrap());
        eprintln!(
            "region B (sigma=0.2): true peak {p:.3} ticks, counts in [{lo}, {hi}], moving {moving}/5000 ticks, {crossings} wall crossings"
        );
        // The paper: persistent oscillation below one encoder tick. Seen by the encoder it is
        // a count toggling between -1 and 0 (one tick peak to peak); the true motion is
        // smaller (chatter across the boundary, see docs/model-notes-firmware.md).
        assert!(p < 1.0, "limit cycle below one tick, got {p}");
        assert_eq!(
            (lo, hi),
            (-1, 0),
            "the count toggles across the wall boundary"
        );
        assert!(
            crossings >= 50,
            "persistent oscillation: {crossings} crossings"
        );
        assert!(moving >= 2500, "persistent motion: {moving} of 5000 ticks");
    }
}

#[test]
fn region_b_with_zero_coulomb_friction() {
    let r = release(B0.sim_plant(), 20.5, 20_000, true);
    let tail = &r.x[15_000..];
    let p = peak(tail);
    let crossings = tail
        .windows(2)
        .filter(|w| (w[0] >= 0.0) != (w[1] >= 0.0))
        .count();
    let s = release(B.sim_plant(), 20.5, 20_000, true);
    let p_sigma = peak(&s.x[15_000..]);
    eprintln!("region B (sigma=0): peak {p:.3} ticks (sigma=0.2: {p_sigma:.3}), {crossings} wall crossings, trip {:?}", r.trip);
    assert_eq!(r.trip, None);
    // Measured, not assumed (see docs/model-notes-firmware.md): persistent, still below one
    // tick here, and larger than with Coulomb friction.
    assert!(crossings >= 50);
    assert!(p < 1.0, "sigma = 0 cycle peak {p}");
    assert!(
        p > p_sigma,
        "sigma = 0 cycle ({p}) larger than sigma = 0.2 ({p_sigma})"
    );
}

#[test]
fn release_across_the_16_bit_counter_wrap_is_bit_identical() {
    // The 16-bit counter reads ⌊x/Δ⌋ − 30, so it crosses 0 ↔ 0xFFFF on every swing of the
    // oscillation (raw counts from −10 down through −30 and below). The firmware's origin is
    // the first reading sign-extended (20 − 30 = −10), so the wall sits at position −30.
    let d = f64::from(board().resolution);
    let run = |offset: i64, wall: i32| {
        let mut plant = C.sim_plant();
        plant.set(20.5 * d, 0.0);
        let mut ch = Channels::new();
        let (sp, _hp) = ch.split();
        let cfg = stiffwall_proto::ServoConfig {
            wall_position: wall,
            ..config(false)
        };
        let mut servo: Servo<'_> = Servo::new(board(), &cfg, sp);
        (0..8000u32)
            .map(|t| tick_offset(&mut servo, &mut plant, t, offset))
            .collect::<Vec<i32>>()
    };
    let plain = run(0, 0);
    let wrapped = run(-30, -30);
    assert_eq!(plain, wrapped);
    // Region C grows until the force clamps (3 N = 30 000 codes), never flipping sign.
    let max = plain.iter().map(|c| c.abs()).max().unwrap();
    eprintln!("counter-wrap run: largest |code| {max}");
    assert_eq!(max, 30_000, "reaches the force limit");
}
