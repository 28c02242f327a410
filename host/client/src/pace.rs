//! How fast a simulated device runs (a leaf module): in real time, as a board would, or as
//! fast as the host reads.

/// How fast the virtual device (or the board emulator) runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Pace {
    /// In real time: one servo period of device time per servo period of wall-clock time.
    #[default]
    RealTime,
    /// As fast as the host reads (device time runs ahead of the wall clock while the host
    /// keeps up): the same counts as in real time, sooner.
    Fast,
}

impl Pace {
    /// [`Pace::Fast`] when `fast` (a front end's `--fast` flag), else [`Pace::RealTime`].
    #[must_use]
    pub fn fast_if(fast: bool) -> Self {
        if fast {
            Self::Fast
        } else {
            Self::RealTime
        }
    }

    /// Whether this is [`Pace::Fast`].
    #[must_use]
    pub fn is_fast(self) -> bool {
        self == Self::Fast
    }
}
