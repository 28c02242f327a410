//! Quadrature encoder on TIM2 (32-bit) in encoder mode 3 (counts every edge of A and B, ×4).
//!
//! Pins: A = PA0 (TIM2_CH1, AF1, Arduino A0 / CN8-1), B = PA1 (TIM2_CH2, AF1, Arduino A1 /
//! CN8-2), 3.3 V logic. Units: raw encoder counts (quadrature edges). Invariants: the counter
//! starts at 0 at boot, counts up when A leads B, and wraps only after 2³² edges (the count is
//! read raw as `u32` and the firmware core unwraps it with `encoder_bits` = 32). A digital input
//! filter (8 samples at the 90 MHz timer clock, ≈ 89 ns) rejects glitches while still following
//! edge rates above 10 MHz. Reading the count is a single 32-bit register read: no side effect,
//! safe from any context.

use stm32f4xx_hal::{
    gpio::{PA0, PA1},
    pac::TIM2,
    qei::Qei,
    rcc::Rcc,
};

/// Input-capture filter code ICxF = 0b0011: f_SAMPLING = f_CK_INT, N = 8.
const INPUT_FILTER: u8 = 0b0011;

/// The encoder interface. One instance (owns TIM2 and PA0/PA1).
pub struct QuadEncoder {
    qei: Qei<TIM2>,
}

impl QuadEncoder {
    /// Configures TIM2 in encoder mode 3 on PA0/PA1 with pull-ups and the input filter, count 0.
    pub fn new(tim: TIM2, a: PA0, b: PA1, rcc: &mut Rcc) -> Self {
        // Pull-ups keep open-collector encoders (and an unplugged cable) at a defined level.
        let a = a.into_alternate::<1>().internal_pull_up(true);
        let b = b.into_alternate::<1>().internal_pull_up(true);
        let mut qei = Qei::new(tim, (a, b), rcc);
        // SAFETY: TIM2 is owned by `qei` (moved in above) and nothing else touches it; this
        // only sets the CC1/CC2 input filter bits while the counter is at rest.
        let regs = unsafe { &*TIM2::ptr() };
        regs.ccmr1_input()
            .modify(|_, w| w.ic1f().set(INPUT_FILTER).ic2f().set(INPUT_FILTER));
        // Mutation check (board emulator): channel 1 inverted, so the count runs backwards.
        #[cfg(feature = "mutant-encoder-polarity")]
        regs.ccer().modify(|_, w| w.cc1p().set_bit());
        qei.set_count(0);
        Self { qei }
    }

    /// The raw 32-bit counter: encoder counts since boot, wrapping (encoder_bits = 32).
    #[inline(always)]
    pub fn raw(&self) -> u32 {
        use stm32f4xx_hal::hal_02::Qei as _;
        self.qei.count()
    }
}

impl stiffwall_firmware::Encoder for QuadEncoder {
    #[inline(always)]
    fn count(&mut self) -> u32 {
        self.raw()
    }
}
