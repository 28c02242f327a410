//! Register names for messages: the registers the image is known to touch by name, every other
//! address by its peripheral block and offset (e.g. "TIM3+0x000 (0x40000400)").
//!
//! Models: nothing (names only). Units: byte addresses of the STM32F446 and Cortex-M4 maps.
//! Invariant: every address gets a name, "unmapped register …" outside the known blocks.

/// Register names for messages: (address, name).
const NAMES: &[(u32, &str)] = &[
    (0x4002_3800, "RCC_CR"),
    (0x4002_3804, "RCC_PLLCFGR"),
    (0x4002_3808, "RCC_CFGR"),
    (0x4002_3884, "RCC_PLLI2SCFGR"),
    (0x4002_3888, "RCC_PLLSAICFGR"),
    (0x4002_388C, "RCC_DCKCFGR"),
    (0x4002_3894, "RCC_DCKCFGR2"),
    (0x4002_3870, "RCC_BDCR"),
    (0x4002_3874, "RCC_CSR"),
    (0x4000_7000, "PWR_CR"),
    (0x4000_7004, "PWR_CSR"),
    (0x4002_3C00, "FLASH_ACR"),
    (0x4002_3C10, "FLASH_CR"),
    (0x4002_3C14, "FLASH_OPTCR"),
    (0xE000_E010, "SYST_CSR"),
    (0xE000_ED04, "SCB_ICSR"),
    (0xE000_ED0C, "SCB_AIRCR"),
    (0xE000_ED88, "SCB_CPACR"),
    (0xE000_EF34, "FPU_FPCCR"),
    (0xE000_1000, "DWT_CTRL"),
    (0xE000_1004, "DWT_CYCCNT"),
    (0xE000_EDFC, "DCB_DEMCR"),
];

/// Peripheral names by base address (for unknown registers).
const BLOCKS: &[(u32, u32, &str)] = &[
    (0x4000_0000, 0x400, "TIM2"),
    (0x4000_0400, 0x400, "TIM3"),
    (0x4000_0800, 0x400, "TIM4"),
    (0x4000_0C00, 0x400, "TIM5"),
    (0x4000_1000, 0x400, "TIM6"),
    (0x4000_1400, 0x400, "TIM7"),
    (0x4000_2800, 0x400, "RTC"),
    (0x4000_2C00, 0x400, "WWDG"),
    (0x4000_3000, 0x400, "IWDG"),
    (0x4000_3800, 0x400, "SPI2"),
    (0x4000_4400, 0x400, "USART2"),
    (0x4000_4800, 0x400, "USART3"),
    (0x4000_5400, 0x400, "I2C1"),
    (0x4000_7000, 0x400, "PWR"),
    (0x4000_7400, 0x400, "DAC"),
    (0x4001_0000, 0x400, "TIM1"),
    (0x4001_1000, 0x400, "USART1"),
    (0x4001_2000, 0x400, "ADC"),
    (0x4001_3800, 0x400, "SYSCFG"),
    (0x4001_3C00, 0x400, "EXTI"),
    (0x4002_0000, 0x2000, "GPIO"),
    (0x4002_3000, 0x400, "CRC"),
    (0x4002_3800, 0x400, "RCC"),
    (0x4002_3C00, 0x400, "FLASH"),
    (0x4002_6000, 0x800, "DMA"),
    (0xE000_0000, 0x1000, "ITM"),
    (0xE000_1000, 0x1000, "DWT"),
    (0xE000_E000, 0x1000, "SCS"),
    (0xE004_2000, 0x1000, "DBGMCU"),
];

/// The register's name for messages, e.g. "RCC_PLLI2SCFGR (0x40023884)" or "TIM3+0x00
/// (0x40000400)".
pub fn reg_name(addr: u32) -> String {
    if let Some((_, n)) = NAMES.iter().find(|(a, _)| *a == addr) {
        return format!("{n} ({addr:#010x})");
    }
    match BLOCKS.iter().find(|(b, l, _)| (*b..b + l).contains(&addr)) {
        Some((b, _, n)) => format!("{n}+{:#05x} ({addr:#010x})", addr - b),
        None => format!("unmapped register {addr:#010x}"),
    }
}

#[cfg(test)]
mod tests {
    use super::reg_name;

    #[test]
    fn known_registers_by_name_others_by_block_and_offset() {
        assert_eq!(reg_name(0x4002_3884), "RCC_PLLI2SCFGR (0x40023884)");
        assert_eq!(reg_name(0x4000_0404), "TIM3+0x004 (0x40000404)");
        assert_eq!(reg_name(0x5000_0000), "unmapped register 0x50000000");
    }
}
