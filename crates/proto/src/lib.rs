//! `stiffwall-proto`: messages between host and firmware (postcard + COBS + CRC-32).
#![no_std]
