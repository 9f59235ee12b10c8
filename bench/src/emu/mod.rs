//! Virtual bench: runs the real firmware ELF on an emulated STM32F103C8 "Blue Pill"
//! (unicorn Cortex-M3 + models of TIM2, DMA1, USART1, GPIO, SysTick, NVIC, RCC). Time is modeled
//! cycles at 72 MHz, from per-instruction costs of the Cortex-M3 TRM (see `cost.rs` and
//! bench/README.md for the model and its expected error). For firmware-in-the-loop tests,
//! the `sim` CLI and the benchmark sweep.
//!
//! ```no_run
//! use ddastep_bench::emu::{firmware_elf, Board};
//! let mut board = Board::load(firmware_elf()?)?;
//! board.run_seconds(0.01)?;
//! println!("{}", board.send_line_wait_ok("G91")?);
//! println!("{}", board.report());
//! # Ok::<(), anyhow::Error>(())
//! ```

pub mod asm;
mod board;
pub mod changes;
mod clock;
pub mod cost;
mod cpu;
pub mod dma;
mod dma_run;
mod dwt;
mod exception;
mod exti;
pub mod figures;
mod firmware;
pub mod floor;
mod gpio;
mod input;
pub mod iwdg;
mod mcu;
pub mod memory;
mod pinmap;
pub mod plant;
pub mod nvic;
pub mod profile;
pub mod pwm;
pub mod qenc;
pub mod ramp_half;
pub mod raster;
mod report;
mod stats;
pub mod summary;
pub mod sender;
pub mod stream;
pub mod sweep;
mod systick;
mod timer;
mod usart;
pub mod usb;
pub mod usb_host;
pub mod usb_splits;
pub mod vcd_out;

pub use board::Board;
pub use cpu::BLUE_PILL;
pub use clock::HZ;
pub use input::{InputFlip, Port};
pub use stats::IsrRun;
pub use mcu::{TIM2_IRQ, USART1_IRQ};
pub use firmware::{firmware_elf, gcode_lines, repo_root, stream_gcode};
pub use gpio::PinEdge;
pub use report::{isr_profile, AxisReport, DmaReport, Report, UsbReport, SpindleReport, StepIsr, AXES, DIR_LOW_IS_POSITIVE, DIR_PINS, EN_PIN, STEP_PINS, TOOL_PINS};
pub use unicorn_engine::RegisterARM;
