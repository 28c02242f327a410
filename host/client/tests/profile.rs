//! A haptic profile over the built-in virtual device (protocol 5): set a three-element profile,
//! read it back, save it with the config; a refused profile names its element and field in
//! words and changes nothing; an empty profile is the config's wall again.

use stiffwall_client::{connect, ClientError, ConnectSpec, Pace};
use stiffwall_proto::profile::{Profile, ProfileElement, Side};
use stiffwall_proto::DamperLaw;

fn three() -> Profile {
    let mut p = Profile::default();
    for e in [
        ProfileElement::Wall {
            position: 2000,
            side: Side::Upper,
            stiffness: 5.0,
            damping: 0.0,
            damper: DamperLaw::DeadBand { counts: 1 },
        },
        ProfileElement::Detents {
            first: -400,
            pitch_counts: 8192.0 / 24.0,
            count: 4,
            strength: 0.01,
            damping: 0.0,
            damper: DamperLaw::Difference,
        },
        ProfileElement::Viscous {
            from: -3000,
            to: -1000,
            damping: 0.001,
            damper: DamperLaw::Difference,
        },
    ] {
        p.elements.push(e).unwrap();
    }
    p
}

#[test]
fn set_get_and_save_a_profile_on_the_virtual_device() {
    let mut c = connect(&ConnectSpec::preset("maxon-re35", Pace::Fast)).unwrap();
    assert_eq!(c.get_profile().unwrap(), Profile::default());
    c.set_profile(&three()).unwrap();
    assert_eq!(c.get_profile().unwrap(), three());
    // A refused profile: the element and the field in words; the active one stays.
    let mut bad = three();
    if let Some(ProfileElement::Detents { pitch_counts, .. }) = bad.elements.get_mut(1) {
        *pitch_counts = 0.5;
    }
    let e = c.set_profile(&bad).unwrap_err();
    assert!(matches!(e, ClientError::Refused { .. }), "{e:?}");
    let text = e.to_string();
    assert!(text.contains("pitch_counts"), "{text}");
    assert_eq!(c.get_profile().unwrap(), three());
    // Saved with the config; a config change keeps it.
    c.save_config().unwrap();
    let cfg = c.get_config().unwrap();
    c.set_config(&cfg).unwrap();
    assert_eq!(c.get_profile().unwrap(), three());
    // The device renders it, and no experiment runs.
    assert_eq!(c.faults().unwrap().latched, 0);
    c.set_profile(&Profile::default()).unwrap();
    assert_eq!(c.get_profile().unwrap(), Profile::default());
}
