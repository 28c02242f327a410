//! Tests of the device's profile requests: `SetProfile` validated, refused while an experiment
//! runs, queued whole and acknowledged; `GetProfile`; `SaveConfig` saving config and profile
//! together and a reboot loading both (the profile on the servo's first tick); a `SetConfig`
//! recompiling the active profile; random `SetProfile` frames never panic the device.

use super::*;
use crate::channels::Channels;
use crate::hal::{HeldCode, SampledCount};
use crate::servo::Servo;
use crate::store::MemStorage;
use core::sync::atomic::Ordering;
use proptest::prelude::*;
use stiffwall_proto::profile::{ProfileElement, ProfileField, Side};
use stiffwall_proto::{encode, DamperLaw, HostMsg, Request};

fn three() -> Profile {
    let mut p = Profile::default();
    for e in [
        ProfileElement::Wall {
            position: 500,
            side: Side::Upper,
            stiffness: 100.0,
            damping: 0.01,
            damper: DamperLaw::DeadBand { counts: 1 },
        },
        ProfileElement::Detents {
            first: -200,
            pitch_counts: 4096.0 / 24.0,
            count: 3,
            strength: 0.05,
            damping: 0.0,
            damper: DamperLaw::Difference,
        },
        ProfileElement::Viscous {
            from: -1000,
            to: -300,
            damping: 0.1,
            damper: DamperLaw::Difference,
        },
    ] {
        p.elements.push(e).unwrap();
    }
    p
}

#[test]
fn set_get_save_and_reboot_with_a_profile() {
    let b = BoardInfo::default();
    let mut ch = Channels::new();
    let (sp, hp) = ch.split();
    let mut dev = Device::new(
        b,
        ConfigStore::new(MemStorage::default()),
        hp,
        ServoConfig::default(),
    );
    let mut servo: Servo<'_> = Servo::new(b, dev.config(), sp);
    assert_eq!(
        dev.handle(HostMsg::GetProfile),
        DeviceMsg::Profile(Profile::default())
    );
    // Refused: element 1's pitch below 2 counts; nothing changes.
    let mut bad = three();
    if let Some(ProfileElement::Detents { pitch_counts, .. }) = bad.elements.get_mut(1) {
        *pitch_counts = 1.0;
    }
    assert!(matches!(
        dev.handle(HostMsg::SetProfile(bad)),
        DeviceMsg::Error {
            code: ErrorCode::InvalidProfile,
            detail: ErrorDetail::ProfileField {
                element: 1,
                field: ProfileField::PitchCounts,
                ..
            }
        }
    ));
    assert_eq!(dev.profile(), &Profile::default());
    assert_eq!(
        dev.handle(HostMsg::SetProfile(three())),
        DeviceMsg::Ack(Request::SetProfile)
    );
    servo.tick(0, &mut SampledCount(600), &mut HeldCode(0));
    assert_eq!(servo.profile().elements().len(), 3);
    assert!(!servo.experiment_running());
    assert_eq!(dev.handle(HostMsg::GetProfile), DeviceMsg::Profile(three()));
    // A config change recompiles the profile (both queued, applied in order).
    let k = ServoConfig {
        stiffness: 50.0,
        ..ServoConfig::default()
    };
    assert_eq!(
        dev.handle(HostMsg::SetConfig(k)),
        DeviceMsg::Ack(Request::SetConfig)
    );
    servo.tick(1, &mut SampledCount(600), &mut HeldCode(0));
    servo.tick(2, &mut SampledCount(600), &mut HeldCode(0));
    assert_eq!(servo.profile().elements().len(), 3);
    // A rate under which element 2's damping is out of range is refused, naming it.
    let fast = ServoConfig {
        servo_rate_hz: 2500,
        ..k
    };
    assert!(matches!(
        dev.handle(HostMsg::SetConfig(fast)),
        DeviceMsg::Error {
            code: ErrorCode::InvalidProfile,
            detail: ErrorDetail::ProfileField {
                element: 2,
                field: ProfileField::Damping,
                ..
            }
        }
    ));
    assert_eq!(
        dev.handle(HostMsg::SaveConfig),
        DeviceMsg::Ack(Request::SaveConfig)
    );
    // Busy while an experiment runs.
    dev.port.shared.experiment.store(true, Ordering::Relaxed);
    assert!(matches!(
        dev.handle(HostMsg::SetProfile(Profile::default())),
        DeviceMsg::Error {
            code: ErrorCode::Busy,
            ..
        }
    ));
    dev.port.shared.experiment.store(false, Ordering::Relaxed);
    // Reboot: config and profile load; the servo takes the profile on its first tick.
    let storage = dev.store_mut().storage_mut().clone();
    drop(servo);
    drop(dev);
    let mut ch2 = Channels::new();
    let (sp2, hp2) = ch2.split();
    let dev2 = Device::new(b, ConfigStore::new(storage), hp2, ServoConfig::default());
    assert_eq!(dev2.config(), &k);
    assert_eq!(dev2.profile(), &three());
    let mut servo2: Servo<'_> = Servo::new(b, dev2.config(), sp2);
    servo2.tick(0, &mut SampledCount(600), &mut HeldCode(0));
    assert_eq!(servo2.profile().elements().len(), 3);
    assert!(!servo2.experiment_running());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]
    /// Random `SetProfile` frames (any element values, any bytes flipped) never panic the
    /// device or its servo, and every frame gets a reply.
    #[test]
    fn random_set_profile_frames_never_panic(
        raw in proptest::collection::vec(
            (any::<u8>(), any::<i32>(), any::<f64>(), any::<u16>(), any::<f32>(), any::<f32>(), any::<u8>()),
            0..=16,
        ),
        flips in proptest::collection::vec((any::<usize>(), any::<u8>()), 0..4),
    ) {
        let mut p = Profile::default();
        for (kind, at, pitch, count, x, y, db) in raw {
            let damper = if db & 1 == 0 { DamperLaw::Difference } else { DamperLaw::DeadBand { counts: db >> 1 } };
            let e = match kind % 4 {
                0 => ProfileElement::Wall { position: at, side: if kind & 4 == 0 { Side::Upper } else { Side::Lower }, stiffness: x, damping: y, damper },
                1 => ProfileElement::Spring { center: at, stiffness: x, damping: y, damper },
                2 => ProfileElement::Detents { first: at, pitch_counts: pitch, count, strength: x, damping: y, damper },
                _ => ProfileElement::Viscous { from: at, to: at.wrapping_add(i32::from(count)), damping: y, damper },
            };
            p.elements.push(e).unwrap();
        }
        let mut buf = [0u8; MAX_FRAME];
        let mut frame = std::vec::Vec::from(encode(&HostMsg::SetProfile(p), &mut buf).unwrap());
        let len = frame.len();
        for (i, v) in flips {
            // Not the delimiter: the frame stays one frame.
            if len > 1 && v != 0 {
                frame[i % (len - 1)] = v;
            }
        }
        let b = BoardInfo::default();
        let mut ch = Channels::new();
        let (sp, hp) = ch.split();
        let mut dev = Device::new(b, ConfigStore::new(MemStorage::default()), hp, ServoConfig::default());
        let mut servo: Servo<'_> = Servo::new(b, dev.config(), sp);
        struct L(std::collections::VecDeque<u8>, usize);
        impl crate::hal::ByteLink for L {
            fn read(&mut self) -> Option<u8> { self.0.pop_front() }
            fn write(&mut self, b: u8) -> bool { if b == 0 { self.1 += 1; } true }
        }
        let mut link = L(frame.into_iter().collect(), 0);
        for t in 0..20u32 {
            dev.poll(t, &mut link);
            let code = servo.tick(t, &mut SampledCount(t.wrapping_mul(977)), &mut HeldCode(0));
            prop_assert!(code.unsigned_abs() <= servo.gains().limit.unsigned_abs());
        }
        prop_assert!(link.1 >= 1, "no reply");
    }
}
