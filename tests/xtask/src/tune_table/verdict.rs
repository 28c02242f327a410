//! What makes the table a failure ([`failures`]): the claims docs/TUNE.md makes, checked row by
//! row.
use super::render::{median, travel_cell};
use super::row::Row;

/// Lower bound of K set / K*_quiet(B set) (docs/TUNE.md and the every-plant test say the same).
const NEAR_OPTIMAL: f64 = 0.7;
/// Lower bound of the median K set / K*(0) over `sim/plants/`.
const MEDIAN_GAIN: f64 = 2.0;

/// What makes the table a failure: a tune that failed, a set wall that does not rest in every
/// run or is unstable, K set below 0.7 × K*(B set) (above K*(B set) only where every run at
/// the set wall rests: the quiet K need not form one interval), a supervisor that did not stop a
/// run, and (over all of `sim/plants/`) a median gain below 2. Empty when the table holds.
pub(super) fn failures(rows: &[Row], whole_family: bool, quick: bool) -> Vec<String> {
    let mut out = Vec::new();
    let mut gains = Vec::new();
    for r in rows {
        let name = &r.case.name;
        if !r.supervisor.all_safe() {
            out.push(format!(
                "{name}: the supervisor did not stop every run at 1.5 K*(B set)"
            ));
        }
        if quick {
            continue;
        }
        let t = match &r.tune {
            Some(Ok(t)) => t,
            Some(Err(e)) => {
                out.push(format!("{name}: tune failed: {e}"));
                continue;
            }
            None => continue,
        };
        gains.push(t.k_set / r.k_star.k_star);
        if t.travel_used.1 {
            out.push(format!(
                "{name}: tune touched an end stop (the plant's trace: {})",
                travel_cell(r)
            ));
        }
        if let Some(a) = &r.at_set {
            if !a.all_rest() {
                out.push(format!(
                    "{name}: the set wall does not rest in every run: {}",
                    a.cell()
                ));
            }
        }
        match &r.k_star_set {
            // Above K*(B) (the top of the first quiet interval) is allowed only because every
            // run at the set wall came to rest (checked above): with a damper the quiet K need
            // not form one interval.
            Some(Ok(k)) => {
                let q = t.k_set / k.k_star;
                if q < NEAR_OPTIMAL {
                    out.push(format!(
                        "{name}: K set / K*(B set) = {q:.3} < {NEAR_OPTIMAL}"
                    ));
                }
            }
            Some(Err(e)) => out.push(format!("{name}: {e}")),
            None => {}
        }
    }
    if whole_family && !quick {
        if let Some(m) = median(&mut gains) {
            if m < MEDIAN_GAIN {
                out.push(format!("median K set / K*(0) = {m:.2} < {MEDIAN_GAIN}"));
            }
        }
    }
    out
}
