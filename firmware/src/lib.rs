//! `stiffwall-firmware`: the hardware-neutral firmware core.
#![no_std]
