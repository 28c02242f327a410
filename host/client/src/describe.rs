//! Device errors and link failures in words: what a refused request or a bad frame means,
//! numbers in a readable form, and which errors are framing replies.

use stiffwall_proto::{ConfigField, DeviceMsg, ErrorCode, ErrorDetail};

/// How a refused field is named in messages: the protocol's own name
/// ([`ConfigField::name`], e.g. `"damping"`) unless a front end supplies its spelling.
pub type FieldLabel = fn(ConfigField) -> &'static str;

/// Renders a device error as a sentence naming the field (by its protocol name) and its range.
#[must_use]
pub fn describe_error(code: ErrorCode, detail: &ErrorDetail) -> String {
    describe_error_named(code, detail, ConfigField::name)
}

/// Renders a device error as a sentence naming the field with `label` and its range.
#[must_use]
pub fn describe_error_named(code: ErrorCode, detail: &ErrorDetail, label: FieldLabel) -> String {
    let what = match code {
        ErrorCode::Oversize => "frame too long",
        ErrorCode::Crc => "CRC mismatch",
        ErrorCode::Cobs => "bad COBS framing",
        ErrorCode::UnknownTag => "unknown message",
        ErrorCode::Deserialize => "malformed message",
        ErrorCode::VersionMismatch => "protocol version mismatch",
        ErrorCode::InvalidConfig => "configuration refused",
        ErrorCode::StoreFailed => "config store failed",
        ErrorCode::Busy => "device busy",
        ErrorCode::InvalidArgument => "argument out of range",
        ErrorCode::QueueFull => "the servo's command queue is full",
        ErrorCode::InvalidProfile => "profile refused",
    };
    match detail {
        ErrorDetail::None => what.to_string(),
        ErrorDetail::Field { field, min, max } => {
            // The device sends f32 bounds; a lower bound of f32::MIN_POSITIVE means "> 0".
            let name = label(*field);
            if *field == ConfigField::Damper {
                // The range is the dead band's, in counts.
                format!(
                    "{what}: {name}: the dead band must be within [{}, {}] counts (use \
                     `difference` for no dead band)",
                    readable(*min),
                    readable(*max)
                )
            } else if *field == ConfigField::TravelMax {
                // The window's ends are whole raw counts; its lower end is min − 1.
                format!(
                    "{what}: {name} must be above {}, within [{min:.0}, {max:.0}] raw counts",
                    label(ConfigField::TravelMin)
                )
            } else if *min == f64::from(f32::MIN_POSITIVE) {
                format!("{what}: {name} must be > 0 and ≤ {}", readable(*max))
            } else {
                format!(
                    "{what}: {name} must be within [{}, {}]",
                    readable(*min),
                    readable(*max)
                )
            }
        }
        ErrorDetail::Version { got, expected } => {
            format!("{what}: device got version {got}, expects {expected}")
        }
        ErrorDetail::Tag(t) => format!("{what}: tag {t}"),
        ErrorDetail::Text(t) => format!("{what}: {t}"),
        ErrorDetail::Repeated { count } => format!("{what} ({count} frames in a row)"),
        ErrorDetail::ProfileField {
            element,
            field,
            min,
            max,
        } => format!(
            "{what}: element {element}: {field} must be within [{}, {}]",
            readable(*min),
            readable(*max)
        ),
    }
}

/// `x` with about 6 significant digits, in scientific notation outside [1e-3, 1e7):
/// `85.4457`, `1.18e-38`, `1048576`.
#[must_use]
pub fn readable(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || !x.is_finite() {
        return x.to_string();
    }
    if !(1e-3..1e7).contains(&a) {
        return format!("{x:.2e}");
    }
    let decimals = (5 - a.log10().floor() as i32).max(0) as usize;
    let s = format!("{x:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// A device reply to a frame that did not decode ([`ErrorCode::is_framing`]).
pub(crate) fn is_framing_reply(m: &DeviceMsg) -> bool {
    matches!(m, DeviceMsg::Error { code, .. } if code.is_framing())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_refused_damper_names_its_dead_band_in_counts() {
        let detail = ErrorDetail::Field {
            field: ConfigField::Damper,
            min: 1.0,
            max: 8.0,
        };
        assert_eq!(
            describe_error(ErrorCode::InvalidConfig, &detail),
            "configuration refused: damper: the dead band must be within [1, 8] counts (use \
             `difference` for no dead band)"
        );
        assert_eq!(
            describe_error_named(ErrorCode::InvalidConfig, &detail, |_| "--damper"),
            "configuration refused: --damper: the dead band must be within [1, 8] counts (use \
             `difference` for no dead band)"
        );
    }

    #[test]
    fn a_refused_travel_window_names_both_ends_in_whole_counts() {
        let detail = ErrorDetail::Field {
            field: ConfigField::TravelMax,
            min: 101.0,
            max: f64::from(i32::MAX),
        };
        assert_eq!(
            describe_error(ErrorCode::InvalidConfig, &detail),
            "configuration refused: travel_max must be above travel_min, within [101, \
             2147483647] raw counts"
        );
        let flag = |f: ConfigField| match f {
            ConfigField::TravelMin => "--travel-min",
            _ => "--travel-max",
        };
        assert_eq!(
            describe_error_named(ErrorCode::InvalidConfig, &detail, flag),
            "configuration refused: --travel-max must be above --travel-min, within [101, \
             2147483647] raw counts"
        );
    }
}
