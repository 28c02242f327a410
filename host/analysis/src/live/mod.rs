//! The data of the live view (`hostctl ui`), computed without its server: the (β, σ) plane
//! ([`plane`]), the (B, K) frontier panel ([`frontier`]) a release test's decimated trace
//! ([`trace`]) and the page's test arguments and telemetry frame ([`wire`]), each as the JSON value or serde type the page receives.
//!
//! Units: as documented per module (dimensionless β, σ, ξ̇; SI B and K; counts in encoder
//! ticks). The axum server, the websocket, its security and control stay in `hostctl`.

pub mod frontier;
pub mod plane;
pub mod trace;
pub mod wire;
