//! placeholder
pub struct Device;
