//! The step output: the engine in the step interrupt (`step.rs`) or in the DMA fill
//! (`burst.rs`), TIM2 set up for it. Built in `init`; rebuilt at rest, with no MCU reset, when
//! a setting changes how (`$2`, `$3`, `$580`, `$581`, a `$0` the DMA layout cannot hold) and
//! when Ctrl-X clears a hard limit's halt. The position and the queue stay in the engine.

use ddastep::grbl::shell::StepOutput;
use ddastep::motion::burst::Burst;
use ddastep::motion::engine::Engine;
use ddastep::motion::shared::Shared;

use super::axes::AXES;
use super::gpio::gpiob;
use super::{burst, pulse, step, tim2};

/// Hands the engine to the output `out` asks for (TIM2 configured for interrupt mode and
/// stopped; it starts in `tim2::start`).
pub fn install(engine: Engine<'static, AXES>, shared: &'static Shared<AXES>, out: &StepOutput<AXES>, nvic: &mut cortex_m::peripheral::NVIC) {
    match out.burst {
        Some((layout, fall)) => {
            let engine = Burst::new(engine, shared, layout.max_tick);
            burst::install(engine, layout, fall, out.pins.dual, nvic);
        }
        None => {
            if out.pins.dual {
                tim2::no_falling_edge();
            }
            step::install(engine, nvic);
        }
    }
}

/// Rebuilds the output at rest (or stopped by a hard limit) as `out` asks, with a pulse of
/// `pulse_ticks`: TIM2 and the output's interrupts stop, the step pins go to their idle level
/// before the new mode runs (dual-edge mode toggles from the levels they have; the enable pin
/// stays as `$4` and the controller set it), the engine takes the pin map, TIM2 starts again.
pub fn rebuild(shared: &'static Shared<AXES>, out: &StepOutput<AXES>, pulse_ticks: u32, nvic: &mut cortex_m::peripheral::NVIC) {
    tim2::stop();
    let mut engine = if burst::active() { burst::uninstall() } else { step::uninstall() };
    // SAFETY: BSRR takes any word; the idle word sets or resets only the step pins.
    gpiob().bsrr().write(|w| unsafe { w.bits(out.pins.idle_word()) });
    engine.rebuild(out.pins, gpiob().odr().read().bits());
    tim2::configure();
    install(engine, shared, out, nvic);
    // (DMA mode: its layout holds the pulse, `StepOutput::of` sized it.)
    let _ = pulse::set_pulse_ticks(pulse_ticks);
    tim2::start();
}
