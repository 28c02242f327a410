//! The paper's analysis of one device (Diolaiti et al. 2006, Sec. III, VII), behind `hostctl
//! analyze` and reused by `tune` and `experiment`: computed and rendered as text by
//! [`stiffwall_analysis::device_report`] (re-exported here, with [`damping`], the spring +
//! damper part), drawn as the (β, σ) figure ([`plot`]) and as the (K, B) frontier figure
//! ([`kb_plot`]) by `stiffwall-figures`.
//!
//! Units: SI as in `stiffwall_analysis::device_report` (kg, N·s/m, N, m, s, N/m, m/s; with
//! `--rotational` kg·m², N·m·s/rad, N·m, rad, N·m/rad, rad/s). Invariants: nothing is computed
//! or drawn here.

pub use stiffwall_analysis::damping;
pub use stiffwall_analysis::device_report::*;
pub use stiffwall_figures::frontier as kb_plot;
pub use stiffwall_figures::plane as plot;
