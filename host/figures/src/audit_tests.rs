//! Tests of every figure's words: each figure, drawn to SVG from small real data, has a title
//! naming the device or plant, axis labels with units, a legend entry for each series drawn and
//! shows all of them ([`crate::describe::audit`]); rotary devices are labelled in N·m/rad and
//! N·m·s/rad, linear ones in N/m and N·s/m, never both.
//!
//! Units: those of each figure. Invariants: the data is small enough for a debug test run.

use crate::atlas::{PanelFigure, SummaryFigure};
use crate::describe::Description;
use crate::figure::audit;
use crate::figure::Figure;
use crate::map::MapFigure;
use crate::plane::{Damper, Plane};
use crate::plant_replay::PlantFigure;
use crate::release::Release;
use crate::trajectory::Trajectory;
use stiffwall_analysis::damping::{damping_report, figure as frontier_figure};
use stiffwall_analysis::device_report::{analyze, Report};
use stiffwall_analysis::map_file::{self, Spec, Values};
use stiffwall_analysis::replay::PlantReplay;
use stiffwall_core::devices;
use stiffwall_sim::exact::History;
use stiffwall_sim::map::{Axis, RunOptions};

fn report(device: &str, damping: Option<f64>) -> Report {
    let p = devices::find(device).unwrap().params;
    let mut r = analyze(Some(device.to_owned()), &p, None, None).unwrap();
    if let Some(b) = damping {
        r.damping = Some(damping_report(&p, b).unwrap());
    }
    r
}

fn assert_clean<F: Figure>(f: &F, size: (u32, u32), rotational: Option<bool>) -> Description {
    let problems = audit(f, size, rotational).unwrap();
    assert!(problems.is_empty(), "{problems:#?}");
    f.describe()
}

#[test]
fn the_plane_names_its_device_units_and_every_series() {
    for (dev, rot) in [("phantom-1.0", false), ("maxon-re35", true)] {
        let r = report(dev, None);
        let d = assert_clean(&Plane::new(&r), crate::plane::SIZE_PX, Some(rot));
        assert!(d.title.starts_with(dev), "{}", d.title);
        let unit = if rot { "N·m/rad" } else { "N/m" };
        assert!(
            d.legend.iter().any(|l| l.contains(&format!(
                "at K = {}",
                crate::describe::sig(r.params.stiffness)
            )) && l.contains(unit)),
            "{:?}",
            d.legend
        );
        assert!(
            d.legend.iter().any(|l| l.starts_with("critical line")),
            "{:?}",
            d.legend
        );
    }
}

#[test]
fn a_damped_wall_is_drawn_apart_from_the_spring_and_not_called_a_region() {
    let r = report("maxon-re35", Some(5e-4));
    let mut p = Plane::new(&r);
    p.velocity_source = "--max-velocity".to_owned();
    let d = assert_clean(&p, crate::plane::SIZE_PX, Some(true));
    assert!(d.title.contains("spring alone"), "{}", d.title);
    let set = d
        .legend
        .iter()
        .find(|l| l.starts_with("the wall with its damper"))
        .unwrap();
    assert!(
        set.contains("B = 5.000e-4 N·m·s/rad")
            && set.contains("the region named is the spring's alone"),
        "{set}"
    );
    assert!(
        d.legend.iter().all(|l| !l.contains("--velocity")),
        "{:?}",
        d.legend
    );
    p.damper = Some(Damper {
        b: 1.0,
        beta_v: 1.0,
        k_max: None,
    });
    assert_clean(&p, crate::plane::SIZE_PX, Some(true));
}

#[test]
fn the_frontier_labels_the_quiet_ceiling_as_drawn_with_units() {
    for (dev, rot) in [("phantom-1.0", false), ("maxon-re35", true)] {
        let r = report(dev, Some(1e-4));
        let f = frontier_figure(r.damping.as_ref().unwrap(), &r.params, Some(dev));
        let d = assert_clean(&f, crate::frontier::SIZE_PX, Some(rot));
        assert!(
            d.legend
                .iter()
                .any(|l| l.starts_with("quiet ceiling 2·max(c, F_s)/Δ = ")),
            "{:?}",
            d.legend
        );
    }
}

#[test]
fn simulate_draws_all_four_energy_terms() {
    let scene =
        stiffwall_sim::scene::Scene::from_toml(include_str!("../../../sim/scenes/base.toml"))
            .unwrap();
    let mut rows = Vec::new();
    scene.simulate(&mut |r| rows.push(*r)).unwrap();
    let f = Trajectory {
        rows: &rows[..rows.len().min(300)],
        name: "base.toml",
    };
    let d = assert_clean(&f, crate::trajectory::SIZE_PX, None);
    for term in [
        "H_T (35)",
        "E_d (28)",
        "E_g (29)",
        "residual of the energy balance (26)",
    ] {
        assert!(
            d.legend.iter().any(|l| l.contains(term)),
            "{term}: {:?}",
            d.legend
        );
    }
    assert!(
        d.axes.contains(&"τ = t/T (periods)".to_owned()),
        "{:?}",
        d.axes
    );
}

fn small_map(xidot0: Vec<f64>) -> map_file::MapFile {
    let spec = Spec {
        mu: Values::One(100.0),
        tau_d: Values::One(0.0),
        xidot0,
        beta: Axis {
            lo: 0.0,
            hi: 1.0,
            n: 4,
        },
        sigma: Axis {
            lo: 0.0,
            hi: 2.0,
            n: 4,
        },
        periods: 200,
        history: History::HoldInitial,
        damping: 0.0,
    };
    map_file::compute(&spec, None, &|| {}, RunOptions::default())
}

#[test]
fn map_and_atlas_figures_have_a_legend_of_every_grey_level_and_line() {
    let one = small_map(vec![5.0]);
    for overlay in [false, true] {
        let f = MapFigure { map: &one, overlay };
        let d = assert_clean(&f, f.size(), None);
        assert_eq!(d.legend.len(), 4 + usize::from(overlay), "{:?}", d.legend);
    }
    let many = small_map(vec![1.0, 5.0, 20.0, 40.0, 80.0]);
    let f = MapFigure {
        map: &many,
        overlay: true,
    };
    assert_clean(&f, f.size(), None);
    let atlas = stiffwall_analysis::atlas::compute(&many).unwrap();
    let panel = PanelFigure {
        map: &many,
        panel: &many.panels[0],
        fractions: stiffwall_analysis::atlas::Line::ALL.map(|l| atlas.panels[0].fraction(l)),
    };
    let d = assert_clean(&panel, crate::atlas::PANEL_PX, None);
    assert_eq!(d.legend.len(), 8, "{:?}", d.legend);
    assert_clean(
        &SummaryFigure { atlas: &atlas },
        crate::atlas::SUMMARY_PX,
        None,
    );
}

#[test]
fn replay_and_release_name_their_plant_and_mark_the_band_and_trip() {
    let trace: Vec<(f64, i64, i64)> = (0..100)
        .map(|i| (f64::from(i) * 1e-3, i64::from(i % 7), i64::from(i % 5)))
        .collect();
    let p = PlantReplay {
        mass: 1e-5,
        viscous: 0.0,
        coulomb: 0.0,
        source: "preset maxon-re35".to_owned(),
        compared: 99,
        runs: 1,
        rms_ticks: 1.5,
        max_ticks: 4,
        starts: Vec::new(),
        trace,
    };
    let d = assert_clean(&PlantFigure(&p), crate::plant_replay::SIZE_PX, None);
    assert!(d.title.contains("preset maxon-re35"), "{}", d.title);
    let mut counts: Vec<i64> = vec![40, 30, 10, -8, -2, 1, 0];
    counts.extend(std::iter::repeat_n(0, 3000));
    let r = report("maxon-re35", None);
    let mut f = Release {
        counts: &counts,
        rate: 1000.0,
        verdict: "settles",
        name: "virtual device",
        stiffness: 2.0,
        damping: 0.0,
        rotary: true,
        trip: None,
        plane: Some(Plane::new(&r)),
    };
    let d = assert_clean(&f, crate::release::SIZE_PX, Some(true));
    assert!(
        d.legend.iter().any(|l| l.starts_with("±1 count")),
        "{:?}",
        d.legend
    );
    assert!(
        d.values[0].starts_with("time axis: the first 0.02000 s of 3.007 s"),
        "{:?}",
        d.values
    );
    f.trip = Some(5);
    f.plane = None;
    f.damping = 1e-3;
    let d = assert_clean(&f, crate::release::SIZE_PX, Some(true));
    assert!(
        d.title
            .contains("K = 2.000 N·m/rad, B = 0.001000 N·m·s/rad"),
        "{}",
        d.title
    );
    assert!(
        d.legend
            .iter()
            .any(|l| l.starts_with("supervisor trip at t = 0.005000 s")),
        "{:?}",
        d.legend
    );
}

#[test]
fn the_kb_map_legends_every_class_chatter_the_ceiling_and_k_max_in_its_units() {
    use stiffwall_analysis::kb::{compute, KbSpec, Plant};
    for (file, rot, k_hi, b_hi) in [
        ("phantom-stiction.toml", false, 4000.0, 5.0),
        ("rotary-realistic.toml", true, 8.0, 0.002),
    ] {
        let path = format!("{}/../../sim/plants/{file}", env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(&path).unwrap();
        let plant = Plant::from_scene_toml(format!("plant file {file}"), &text).unwrap();
        let spec = KbSpec {
            k: Axis {
                lo: k_hi / 10.0,
                hi: k_hi,
                n: 3,
            },
            b: Axis {
                lo: 0.0,
                hi: b_hi,
                n: 3,
            },
            xidot0: 5.0,
            velocity: 0.0,
            periods: 200,
            history: History::HoldInitial,
            damper: stiffwall_sim::rich::WallDamper::DeadBand(1),
        };
        let m = compute(&plant, &spec, &|| {});
        let f = crate::kb_map::KbFigure(&m);
        let d = assert_clean(&f, crate::kb_map::SIZE_PX, Some(rot));
        assert!(
            d.title.starts_with(&format!("plant file {file}")),
            "{}",
            d.title
        );
        assert_eq!(d.legend.len(), 7, "{:?}", d.legend);
        assert!(
            d.legend.iter().any(|l| l.starts_with("chatter")),
            "{:?}",
            d.legend
        );
    }
}
