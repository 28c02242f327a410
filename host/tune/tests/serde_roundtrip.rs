//! The tune's report and its progress events read back what they write: a real dry-run tune
//! of the fast virtual device, its [`Outcome`] and every [`Progress`] event serialized to JSON
//! and deserialized again.

use stiffwall_client::{connect, Cancel, ConnectSpec, Pace};
use stiffwall_tune::{tune, Outcome, Progress, Settings};

#[test]
fn an_outcome_and_its_progress_events_round_trip_through_json() {
    let mut client = connect(&ConnectSpec::preset("maxon-re35", Pace::Fast)).unwrap();
    let settings = Settings {
        dry_run: true,
        ..Settings::default()
    };
    let mut events = Vec::new();
    let outcome = tune(&mut client, &settings, &Cancel::default(), &mut |e| {
        events.push(e);
    })
    .unwrap();

    let json = serde_json::to_value(&outcome).unwrap();
    let back: Outcome = serde_json::from_value(json.clone()).unwrap();
    assert_eq!(serde_json::to_value(&back).unwrap(), json);
    assert_eq!(back.k_set, outcome.k_set);
    assert_eq!(back.frontier, outcome.frontier);
    assert_eq!(back.verification, outcome.verification);

    assert!(events.len() > 3, "{events:?}");
    for e in &events {
        let text = serde_json::to_string(e).unwrap();
        let back: Progress = serde_json::from_str(&text).unwrap();
        assert_eq!(&back, e, "{text}");
    }
}
