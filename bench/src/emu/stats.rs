//! Run statistics kept while the board runs: sleep time per 1 ms window (the not-asleep load),
//! handler-mode time per window (the interrupt load) and the step interrupt's modeled
//! duration, instruction count and update-to-BSRR offset.
//! For `board.rs` (collection) and `report.rs` (output).

/// Modeled cycles per CPU-load window (1 ms at 72 MHz).
pub const WINDOW: u64 = 72_000;

/// A TIM2 handler in progress.
#[derive(Clone, Copy, Debug)]
pub struct IsrEntry {
    /// Cycle the exception entry began.
    pub start: u64,
    pub insns: u64,
    /// Cycle of the update event when UIF was set at entry.
    pub update: Option<u64>,
    /// TIM2 events that had found their flag still set, counted at entry.
    pub overruns: u64,
}

/// Aggregates over all TIM2 handler runs.
#[derive(Clone, Debug, Default)]
pub struct IsrStats {
    pub entries: u64,
    pub cycles_sum: u64,
    pub cycles_min: Option<u64>,
    pub cycles_max: u64,
    pub insns_sum: u64,
    pub insns_max: u64,
    pub bsrr_min: Option<u64>,
    pub bsrr_max: Option<u64>,
}

/// One run of the TIM2 handler (the per-entry log, `Board::set_isr_log`).
#[derive(Clone, Debug)]
pub struct IsrRun {
    /// Cycle the exception entry began.
    pub start: u64,
    /// Modeled cycles from entry to the end of the return (or the last instruction before a
    /// tail-chain).
    pub cycles: u64,
    /// Cycle of the update event when UIF was set at entry.
    pub update: Option<u64>,
    /// Cycle of the handler's first GPIOB BSRR/BRR store.
    pub bsrr: Option<u64>,
    /// TIM2 events that had found their flag still set, counted at entry (a rise from one
    /// run to the next: this run was entered after an overrun).
    pub overruns: u64,
    /// Start addresses of the translated blocks it ran, in order.
    pub blocks: Vec<u32>,
}

/// Everything collected during a run.
#[derive(Default)]
pub struct Stats {
    /// Sleeping cycles per window.
    pub sleep: Vec<u64>,
    /// Cycle of the first sleep (WFI) after reset: the end of boot.
    pub first_sleep: Option<u64>,
    pub isr: Option<IsrEntry>,
    pub step_isr: IsrStats,
    /// TIM2 handler cycles per window (entry to end of return).
    pub isr_busy: Vec<u64>,
    /// Handler-mode cycles per window: any exception, from the entry that leaves thread mode
    /// to the return that goes back to it (nesting and tail-chains included once).
    pub handler_busy: Vec<u64>,
    /// Cycle the running stretch of handler mode began.
    pub handler_since: Option<u64>,
    /// Every TIM2 handler run, while the per-entry log is on.
    pub isr_log: Option<Vec<IsrRun>>,
}

impl Stats {
    // record sleep from cycle `from` to `to`
    pub fn sleep(&mut self, from: u64, to: u64) {
        if to > from && self.first_sleep.is_none() {
            self.first_sleep = Some(from);
        }
        add_per_window(&mut self.sleep, from, to);
    }

    // an exception is entered at cycle `at` (from thread mode, or nested / tail-chained)
    pub fn handler_enter(&mut self, at: u64) {
        self.handler_since.get_or_insert(at);
    }

    // the CPU goes back to thread mode (or sleeps on exit) at cycle `at`
    pub fn handler_leave(&mut self, at: u64) {
        if let Some(s) = self.handler_since.take() {
            add_per_window(&mut self.handler_busy, s, at);
        }
    }

    // close the running TIM2 handler at cycle `end` with `insns` executed so far
    pub fn isr_done(&mut self, end: u64, insns: u64, first_bsrr: Option<u64>, blocks: Vec<u32>) {
        let Some(e) = self.isr.take() else { return };
        if let Some(log) = &mut self.isr_log {
            log.push(IsrRun { start: e.start, cycles: end - e.start, update: e.update, bsrr: first_bsrr, overruns: e.overruns, blocks });
        }
        let s = &mut self.step_isr;
        let cycles = end - e.start;
        let n = insns - e.insns;
        add_per_window(&mut self.isr_busy, e.start, end);
        s.entries += 1;
        s.cycles_sum += cycles;
        s.cycles_max = s.cycles_max.max(cycles);
        s.cycles_min = Some(s.cycles_min.map_or(cycles, |m| m.min(cycles)));
        s.insns_sum += n;
        s.insns_max = s.insns_max.max(n);
        if let (Some(u), Some(b)) = (e.update, first_bsrr) {
            let off = b - u;
            s.bsrr_min = Some(s.bsrr_min.map_or(off, |m| m.min(off)));
            s.bsrr_max = Some(s.bsrr_max.map_or(off, |m| m.max(off)));
        }
    }

    // CPU load of the busiest complete window that starts after boot (the first sleep) and
    // ends before cycle `now`; 0 before the first sleep. Boot runs init with interrupts off
    // (clocks, ramp table), which would read as 100 %.
    pub fn cpu_load_peak(&self, now: u64) -> f64 {
        match self.first_sleep {
            Some(s) => self.peak_windows(s.div_ceil(WINDOW) as usize, now),
            None => 0.0,
        }
    }

    // CPU load of the busiest complete window before cycle `now`, boot included
    pub fn cpu_load_peak_with_boot(&self, now: u64) -> f64 {
        self.peak_windows(0, now)
    }

    fn peak_windows(&self, first: usize, now: u64) -> f64 {
        self.peak_of(first, now, |w| self.window_load(w))
    }

    // busiest complete window after boot (see `cpu_load_peak`) by `load`
    fn peak_after_boot(&self, now: u64, load: impl Fn(usize) -> f64) -> f64 {
        match self.first_sleep {
            Some(s) => self.peak_of(s.div_ceil(WINDOW) as usize, now, load),
            None => 0.0,
        }
    }

    fn peak_of(&self, first: usize, now: u64, load: impl Fn(usize) -> f64) -> f64 {
        (first..(now / WINDOW) as usize).map(load).fold(0.0, f64::max)
    }

    // interrupt load (handler mode, every exception) of the busiest complete window after boot
    pub fn interrupt_load_peak(&self, now: u64) -> f64 {
        self.peak_after_boot(now, |w| self.window_interrupt_load(w))
    }

    // step interrupt's share of the busiest complete window after boot
    pub fn step_isr_load_peak(&self, now: u64) -> f64 {
        self.peak_after_boot(now, |w| self.window_isr_load(w))
    }

    // fraction of window `w` in handler mode
    pub fn window_interrupt_load(&self, w: usize) -> f64 {
        *self.handler_busy.get(w).unwrap_or(&0) as f64 / WINDOW as f64
    }

    // fraction of window `w` spent in the TIM2 handler
    pub fn window_isr_load(&self, w: usize) -> f64 {
        *self.isr_busy.get(w).unwrap_or(&0) as f64 / WINDOW as f64
    }

    // busy fraction of window `w`
    pub fn window_load(&self, w: usize) -> f64 {
        1.0 - *self.sleep.get(w).unwrap_or(&0) as f64 / WINDOW as f64
    }

    // CPU load over windows [from, to) (cycles), averaged
    pub fn cpu_load_between(&self, from: u64, to: u64) -> f64 {
        let (a, b) = ((from / WINDOW) as usize, (to / WINDOW) as usize);
        if b <= a {
            return 0.0;
        }
        let slept: u64 = (a..b).map(|w| *self.sleep.get(w).unwrap_or(&0)).sum();
        1.0 - slept as f64 / ((b - a) as u64 * WINDOW) as f64
    }
}

// add the cycles of [from, to) to the per-window totals `v`
fn add_per_window(v: &mut Vec<u64>, from: u64, to: u64) {
    let mut t = from;
    while t < to {
        let w = (t / WINDOW) as usize;
        let upto = to.min((w as u64 + 1) * WINDOW);
        if v.len() <= w {
            v.resize(w + 1, 0);
        }
        v[w] += upto - t;
        t = upto;
    }
}
