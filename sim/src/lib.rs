//! `stiffwall-sim`: plants and solvers for the haptic loop of eq. (7)–(9).
#![cfg_attr(not(feature = "std"), no_std)]
