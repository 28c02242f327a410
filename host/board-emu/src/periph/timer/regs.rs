//! The timers' register indices (offset / 4) and control bits, shared by the shared model
//! (`timer/mod.rs`), its three users (`tim1`, `tim2`, `tim7`) and the force output (a leaf).

/// TIMx_CR1 (register index, offset / 4).
pub(crate) const CR1: usize = 0;
/// TIMx_SMCR.
pub(crate) const SMCR: usize = 2;
/// TIMx_DIER.
pub(crate) const DIER: usize = 3;
/// TIMx_SR.
pub(crate) const SR: usize = 4;
/// TIMx_EGR.
pub(crate) const EGR: usize = 5;
/// TIMx_CCMR1.
pub(crate) const CCMR1: usize = 6;
/// TIMx_CCER.
pub(crate) const CCER: usize = 8;
/// TIMx_CNT.
pub(crate) const CNT: usize = 9;
/// TIMx_PSC.
pub(crate) const PSC: usize = 10;
/// TIMx_ARR.
pub(crate) const ARR: usize = 11;
/// TIMx_CCR1.
pub(crate) const CCR1: usize = 13;
/// TIMx_BDTR (TIM1 only).
pub(crate) const BDTR: usize = 17;

/// CR1.CEN.
pub(crate) const CR1_CEN: u32 = 1;
/// CR1.URS: only overflow sets UIF.
pub(crate) const CR1_URS: u32 = 1 << 2;
/// CR1.DIR: counting down.
pub(crate) const CR1_DIR: u32 = 1 << 4;
/// CR1.ARPE: ARR is buffered.
pub(crate) const CR1_ARPE: u32 = 1 << 7;
/// SR.UIF and EGR.UG.
pub(crate) const UPDATE: u32 = 1;
/// SR / DIER bits that raise the interrupt line: UIF, CC1IF–CC4IF, TIF.
pub(crate) const LINE_FLAGS: u32 = 0x5F;
