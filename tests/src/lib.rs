//! Support code for the cross-crate software-in-the-loop tests in `tests/tests/`.
