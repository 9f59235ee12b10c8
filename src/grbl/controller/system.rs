//! Grbl's `$` system commands: help, `$$`, `$#`, `$G`, `$I`, `$I=`, `$N`, `$Nn=`, `$C`, `$X`,
//! `$H`, `$J=`, `$SLP`, `$RST=$/#/*`, and `$N=value` settings. Long listings are written a line
//! at a time as TX room appears.

use super::{Controller, Listing};
use crate::grbl::chip;
use crate::grbl::coords::Coords;
use crate::grbl::gcode;
use crate::num::u32_of;
use crate::error::Error;
use crate::grbl::reply::Out;
use crate::grbl::report::{self, PARAM_LINES, SETTING_LEN};
use crate::grbl::settings::{Change, Settings};
use crate::grbl::store::{Text, STARTUP_LINES, TEXT_LEN};

impl<const N: usize> Controller<'_, N> {
    /// A `$` line (without the `$`).
    #[inline(never)]
    pub(super) fn system(&mut self, cmd: &[u8], out: &mut impl Out) -> Result<(), Error> {
        // Grbl: `$$`, `$#`, `$I`, `$N`, `$RST`, settings need Idle or Alarm (not Check).
        let idle = self.drained() && !self.check && !self.jogging();
        let need_idle = |ok: bool| if ok { Ok(()) } else { Err(Error::NotIdle) };
        // A part that failed the chip check answers only the reports (`$`, `$$`, `$#`, `$G`,
        // `$I`, `$N`, `$ENC`): a line that would move, unlock or write is grblHAL's error:49.
        if !matches!(cmd, [] | [b'$' | b'#' | b'G' | b'I' | b'N'] | b"ENC") && self.refuse(out) {
            return Err(Error::SelfTestFailed);
        }
        match cmd {
            b"" => out.put(report::HELP),
            b"G" => report::modes(out, &self.modal),
            // Grbl's error:13: `$X` and `$H` wait for the safety door to close.
            b"X" | [b'H', ..] if self.door_pin => return Err(Error::CheckDoor),
            b"X" if self.alarm => {
                self.alarm = false;
                out.put(report::UNLOCKED);
            }
            b"X" => {}
            b"ENC" => self.encoder_report(out)?,
            [b'H', rest @ ..] if rest.len() < 2 => self.home_start(rest.first().copied(), out)?,
            b"C" if self.check => {
                // Leaving check mode resets, as in Grbl: state and position as before `$C`.
                out.put(report::CHECK_OFF);
                self.reset_after = true;
            }
            b"C" => {
                need_idle(idle && !self.alarm)?;
                self.check = true;
                out.put(report::CHECK_ON);
            }
            b"$" => {
                need_idle(idle || self.check)?;
                self.start_listing(Listing::Settings(0), out);
            }
            b"#" => {
                need_idle(idle)?;
                self.start_listing(Listing::Params(0), out);
            }
            b"I" => {
                need_idle(idle)?;
                report::build_info(out, self.stored.build_info.as_bytes(), self.feeder.capacity(), &self.ramped);
                self.start_listing(Listing::Info, out);
            }
            [b'I', b'=', text @ ..] => {
                need_idle(idle)?;
                if !self.stored.build_info.set(text) {
                    return Err(Error::LineLengthExceeded);
                }
                self.save_later(out);
            }
            b"N" => {
                need_idle(idle)?;
                for (i, t) in self.stored.startup.iter().enumerate() {
                    crate::grbl::reply::put_u32_after(out, b"$N", i as u32);
                    out.put(b"=");
                    out.put(t.as_bytes());
                    out.put(b"\r\n");
                }
            }
            [b'N', rest @ ..] => self.store_startup(rest, idle && !self.alarm, out)?,
            b"SLP" => {
                need_idle(idle)?;
                out.put(report::SLEEPING);
                self.sleep = true;
                self.drivers_on = false;
            }
            &[b'R', b'S', b'T', b'=', what @ (b'$' | b'*' | b'#')] => {
                need_idle(idle)?;
                out.put(report::RESTORED);
                if what != b'$' {
                    self.stored.coords = Coords::ZERO;
                }
                if what == b'*' {
                    self.stored.startup = [Text::EMPTY; STARTUP_LINES];
                    self.stored.build_info = Text::EMPTY;
                }
                if what != b'#' {
                    let old = self.settings;
                    self.settings = Settings::DEFAULT;
                    if !old.same_pins::<N>(&self.settings) || old.dma_burst != self.settings.dma_burst {
                        self.settings_changed(Change::Pins, out);
                    }
                    self.settings_changed(Change::Profile, out);
                }
                self.save_later(out);
                // Grbl resets after a restore (the banner follows the `ok`).
                self.reset_after = true;
            }
            [b'J', b'=', text @ ..] => self.jog_line(text, out)?,
            [b'0'..=b'9', ..] => {
                let mut i = 0;
                let id = gcode::parse_number(cmd, &mut i)?;
                if cmd.get(i) != Some(&b'=') {
                    return Err(Error::InvalidStatement);
                }
                i += 1;
                let value = gcode::parse_number(cmd, &mut i)?;
                if i != cmd.len() || id > u16::MAX as f32 || id != libm::truncf(id) {
                    return Err(Error::InvalidStatement);
                }
                need_idle(idle)?;
                let change = self.settings.set(u32_of(id) as u16, value, N)?;
                self.settings_changed(change, out);
            }
            _ => return Err(Error::InvalidStatement),
        }
        Ok(())
    }

    /// Starts a long listing (`$$`, `$#`, the end of `$I`).
    fn start_listing(&mut self, l: Listing, out: &mut impl Out) {
        self.new_job().listing = Some(l);
        self.advance(false, out);
    }

    /// `$Nn=line`: the line runs (as Grbl checks it, by executing it) and is stored if valid.
    fn store_startup(&mut self, rest: &[u8], idle: bool, out: &mut impl Out) -> Result<(), Error> {
        let mut i = 0;
        let n = gcode::parse_number(rest, &mut i)?;
        if rest.get(i) != Some(&b'=') {
            return Err(Error::InvalidStatement);
        }
        let line = &rest[i + 1..];
        if !idle {
            return Err(Error::NotIdle);
        }
        let slot = libm::truncf(n);
        if !(0.0..STARTUP_LINES as f32).contains(&slot) {
            return Err(Error::InvalidStatement);
        }
        if line.len() > TEXT_LEN {
            return Err(Error::LineLengthExceeded);
        }
        self.gcode(line, out)?;
        if let Some(s) = self.stored.startup.get_mut(u32_of(slot) as usize) {
            s.set(line);
        }
        self.save_later(out);
        Ok(())
    }

    /// Follows a settings change through (only ever called while idle); the line's `ok` waits
    /// for the poll that asks for the flash write.
    fn settings_changed(&mut self, change: Change, out: &mut impl Out) {
        if change != Change::None {
            self.save_later(out);
        }
        if change == Change::Pins {
            // (The mode sets the timing too: the profile follows.)
            self.feeder.set_pins(self.settings.pins());
            self.reinit = true;
        }
        match change {
            Change::None | Change::Shell => {}
            Change::Pins | Change::Profile => {
                self.axes = self.settings.axis_count(N);
                self.limits = self.settings.planner_limits(self.ramped.cfg.vmax);
                self.apply_profile();
                self.sync_planner();
            }
        }
        // Any change re-zeroes the encoder check (settings change only at rest).
        self.enc_configure();
    }

    /// Writes listing lines while they fit; the listing left, if any.
    #[inline(never)]
    pub(super) fn list(&self, mut l: Listing, out: &mut impl Out) -> Option<Listing> {
        loop {
            match l {
                Listing::Settings(i) => {
                    let id = Settings::id(i as usize, self.axes)?;
                    if out.room() < SETTING_LEN + 4 {
                        return Some(l);
                    }
                    let (v, d) = self.settings.get(id, self.axes).unwrap_or((0.0, 0));
                    report::setting(out, id, v, d);
                    l = Listing::Settings(i + 1);
                }
                Listing::Params(i) => {
                    if i as usize >= PARAM_LINES {
                        return None;
                    }
                    if out.room() < report::param_len(N) + 4 {
                        return Some(l);
                    }
                    report::param::<N>(out, i as usize, &self.offsets, self.axes);
                    l = Listing::Params(i + 1);
                }
                Listing::Info => {
                    if out.room() < chip::REPORT_LEN + report::STEP_TIME_LEN + 4 {
                        return Some(l);
                    }
                    if let Some(c) = &self.chip {
                        chip::report(out, c);
                    }
                    if let Some(t) = crate::steptime::STEP_TIME.take() {
                        report::step_time(out, &t, self.ramped.dma);
                    }
                    return None;
                }
            }
        }
    }
}
