//! What the telemetry session of `stiffwall-client` (plan, pump, recorder) needs from the
//! command line: the Ctrl-C handler that cancels [`stiffwall_client::ctrl_c`] and a recording
//! header described from the `--port/--device/…` options.

use crate::device::connect::ConnectArgs;
use stiffwall_client::{header_for_target, Client, Header};
use stiffwall_proto::ServoConfig;

/// Makes Ctrl-C cancel [`stiffwall_client::ctrl_c`] (once per process; later calls
/// keep the first handler).
pub fn stop_on_ctrl_c() {
    let _ = ctrlc::set_handler(|| stiffwall_client::ctrl_c().cancel());
}

/// Header facts of a recording made through `client` now, its target described from `connect`.
pub fn header(
    client: &Client,
    cfg: ServoConfig,
    decimation: u16,
    connect: Option<&ConnectArgs>,
) -> Header {
    let virtual_plant =
        connect.and_then(|c| (c.port.is_none() && !c.qemu).then(|| c.virtual_plant_name()));
    let target = connect.map_or_else(|| "device".to_string(), ConnectArgs::describe);
    header_for_target(client, cfg, decimation, target, virtual_plant)
}
