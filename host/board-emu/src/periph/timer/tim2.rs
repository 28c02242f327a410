//! TIM2, the encoder interface: a 32-bit general-purpose timer whose counter follows the
//! plant's encoder count (TI1/TI2 in encoder mode), read by the servo loop every tick.
//!
//! Models: SMCR.SMS 1–3 (mode 3 counts every edge of both channels, the ×4 count; modes 1 and
//! 2 half of it), CCMR1.CC1S = CC2S = 1, CCER.CC1P/CC2P (each inverts the direction), CNT
//! (reads the plant's count since the last rebase, wrapped at ARR + 1; writes rebase it),
//! CR1.CEN (stopping freezes the count) and CR1.DIR (follows the last movement), EGR.UG
//! (reloads PSC and ARR, the count restarts at 0), ARR, SR (rc_w0), the rest latched.
//! Refuses: a running TIM2 that is not an encoder interface; offsets from 0x54 on. Units:
//! counts (the image's rig Δ per count, see `plant`). Invariant: CNT = base count + (plant
//! count − plant count at the base), so the count is exact however long between reads.

use super::regs::{ARR, CCER, CCMR1, CNT, CR1, CR1_DIR, EGR, PSC, SMCR, SR};
use crate::periph::state::Periph;

/// TIM2 base address.
pub const BASE: u32 = 0x4000_0000;
/// Last modelled word address (OR).
pub const LAST: u32 = 0x4000_0053;
/// ARR at reset (32-bit counter).
const ARR_RESET: u32 = u32::MAX;

/// TIM2 at reset: the count restarts from the plant's position now.
pub(crate) fn reset(p: &mut Periph) {
    p.tim2.reset(ARR_RESET);
    p.enc_base_plant = p.plant.count();
    p.enc_base_cnt = 0;
}

/// A word read of a TIM2 register; CNT is the encoder count now.
pub(crate) fn read(p: &mut Periph, a: u32) -> u32 {
    let i = ((a - BASE) / 4) as usize;
    if i == CNT {
        count(p) as u32
    } else {
        p.tim2.r[i]
    }
}

/// A word write of a TIM2 register.
pub(crate) fn write(p: &mut Periph, a: u32, v: u32) {
    let i = ((a - BASE) / 4) as usize;
    match i {
        CNT => rebase(p, u64::from(v)),
        CR1 => {
            let cnt = count(p);
            p.tim2.r[CR1] = v;
            rebase(p, cnt);
        }
        SR => p.tim2.r[SR] &= v,
        EGR => {
            if v & 1 != 0 {
                p.tim2.arr = p.tim2.r[ARR];
                p.tim2.psc = p.tim2.r[PSC];
                rebase(p, 0);
            }
        }
        ARR => {
            p.tim2.r[ARR] = v;
            p.tim2.arr = v;
        }
        _ => p.tim2.r[i] = v,
    }
}

/// The encoder count TIM2 shows now.
fn count(p: &mut Periph) -> u64 {
    let t = &p.tim2;
    let sms = t.r[SMCR] & 7;
    if !t.running() {
        return p.enc_base_cnt;
    }
    let ccmr1 = t.r[CCMR1];
    let encoder = matches!(sms, 1..=3) && ccmr1 & 3 == 1 && (ccmr1 >> 8) & 3 == 1;
    if !encoder {
        p.fail(format!(
            "TIM2 runs but is not an encoder interface: TIM2_SMCR.SMS = {sms} (allowed 1-3), \
             TIM2_CCMR1.CC1S = {} and CC2S = {} (allowed 1: TI1/TI2 inputs)",
            ccmr1 & 3,
            (ccmr1 >> 8) & 3
        ));
        return p.enc_base_cnt;
    }
    let ccer = t.r[CCER];
    let inverted = ((ccer >> 1) & 1) ^ ((ccer >> 5) & 1) == 1;
    let now_count = p.plant.count_at(p.now);
    let mut delta = now_count - p.enc_base_plant;
    if sms != 3 {
        // Modes 1 and 2 count the edges of one channel only: half the ×4 count.
        delta = delta.div_euclid(2);
    }
    if inverted {
        delta = -delta;
    }
    let modulo = i128::from(p.tim2.arr) + 1;
    let cnt = (i128::from(p.enc_base_cnt) + i128::from(delta)).rem_euclid(modulo) as u64;
    // The DIR bit of CR1 follows the last movement.
    if delta < 0 {
        p.tim2.r[CR1] |= CR1_DIR;
    } else if delta > 0 {
        p.tim2.r[CR1] &= !CR1_DIR;
    }
    cnt
}

/// The count restarts at `cnt` from the plant's position now.
fn rebase(p: &mut Periph, cnt: u64) {
    p.enc_base_cnt = cnt;
    p.enc_base_plant = p.plant.count_at(p.now);
}

#[cfg(test)]
mod tests {
    use crate::periph::state::Periph;
    use crate::plant::Coupling;

    #[test]
    fn tim2_follows_the_encoder_with_direction_polarity_and_wrap() {
        use stiffwall_sim::rich::{PlantModel, RichPlant};
        let delta = std::f64::consts::TAU / 8192.0;
        let model = PlantModel::rigid(1e-5, 1e-5, 1e-3, delta).unwrap();
        let mut plant = RichPlant::new(&model).unwrap();
        plant.set_state(0.0, 0.0);
        let mut p = Periph::new(Coupling::new(Some(plant)));
        p.write(0x4000_0008, 4, 3); // SMCR.SMS = 3: encoder mode 3
        p.write(0x4000_0018, 4, 0x0101); // CC1S = CC2S = 1
        p.write(0x4000_0024, 4, 0); // CNT = 0
        p.write(0x4000_0000, 4, 1); // CEN
                                    // The plant moves backwards 5.5 counts: floor gives -6, the 32-bit counter wraps.
        p.plant = {
            let mut pl = RichPlant::new(&model).unwrap();
            pl.set_state(-5.5 * delta, 0.0);
            Coupling::new(Some(pl))
        };
        assert_eq!(p.read(0x4000_0024, 4), u64::from(u32::MAX - 5));
        assert_eq!(
            p.read(0x4000_0000, 4) & 0x10,
            0x10,
            "CR1.DIR: counting down"
        );
        p.write(0x4000_0020, 4, 0b10); // CC1P: channel 1 inverted, the count runs the other way
        assert_eq!(p.read(0x4000_0024, 4), 6);
        assert!(p.stop.is_none(), "{:?}", p.stop);
    }
}
