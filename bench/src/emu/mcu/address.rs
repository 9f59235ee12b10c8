//! Peripheral base and register addresses of the STM32F103 (RM0008 §3.3, the Cortex-M3's
//! private peripheral bus) that the MMIO dispatch routes; a leaf for `mcu.rs` and `mmio.rs`.

pub(super) const TIM2: u32 = 0x4000_0000;
pub(super) const TIM1: u32 = 0x4001_2C00;
pub(super) const TIM3: u32 = 0x4000_0400;
pub(super) const USART1: u32 = 0x4001_3800;
pub(super) const USB: u32 = crate::emu::usb::REGS;
pub(super) const USB_PMA: u32 = crate::emu::usb::PMA;
pub(super) const GPIOA: u32 = 0x4001_0800;
pub(super) const RCC: u32 = 0x4002_1000;
pub(super) const DMA1: u32 = 0x4002_0000;
pub(super) const IWDG: u32 = 0x4000_3000;
pub(super) const EXTI: u32 = 0x4001_0400;
pub(super) const AFIO_EXTICR1: u32 = 0x4001_0008;
pub(super) const RCC_CSR: u32 = 0x4002_1024;
pub(super) const FLASH_IF: u32 = 0x4002_2000;
pub(super) const RCC_CFGR: u32 = 0x4002_1004;
pub(super) const SCS: u32 = 0xE000_E000;
pub(super) const DWT_CTRL: u32 = 0xE000_1000;
pub(super) const DWT_CYCCNT: u32 = 0xE000_1004;
pub(super) const DEMCR: u32 = 0xE000_EDFC;
pub(super) const CPUID: u32 = ddastep::grbl::chip::CPUID_ADDR;
