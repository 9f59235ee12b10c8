//! Grbl's `$` system commands: help, `$$`, `$#`, `$G`, `$I`, `$N`, `$X`, `$H`, `$RST=`, and
//! `$N=value` settings. Long listings are written a line at a time as TX room appears.

use super::{Controller, Job, Listing};
use crate::gcode;
use crate::planner::Limits;
use crate::protocol::{Error, Out};
use crate::report::{self, PARAM_LINES, SETTING_LEN};
use crate::settings::{Change, Settings};

impl<const N: usize> Controller<'_, N> {
    /// A `$` line (without the `$`).
    pub(super) fn system(&mut self, cmd: &[u8], out: &mut impl Out) -> Result<(), Error> {
        let idle = self.drained();
        let need_idle = |idle: bool| if idle { Ok(()) } else { Err(Error::NotIdle) };
        match cmd {
            b"" => out.put(report::HELP),
            b"G" => report::modes(out, &self.modal),
            b"X" if self.alarm => {
                self.alarm = false;
                out.put(report::UNLOCKED);
            }
            b"X" => {}
            b"H" => return Err(Error::SettingDisabled),
            b"$" => {
                need_idle(idle)?;
                self.start(Job { listing: Some(Listing::Settings(0)), ..Job::NONE }, out);
            }
            b"#" => {
                need_idle(idle)?;
                self.start(Job { listing: Some(Listing::Params(0)), ..Job::NONE }, out);
            }
            b"I" => {
                need_idle(idle)?;
                report::build_info(out, self.feeder.capacity(), &self.ramped);
                if let Some(t) = crate::steptime::STEP_TIME.take() {
                    report::step_time(out, &t);
                }
            }
            b"N" => {
                need_idle(idle)?;
                out.put(b"$N0=\r\n$N1=\r\n");
            }
            b"RST=$" | b"RST=*" | b"RST=#" => {
                need_idle(idle)?;
                out.put(report::RESTORED);
                if cmd != b"RST=#" {
                    self.settings = Settings::DEFAULT;
                    self.settings_changed(Change::Pins, out);
                    self.settings_changed(Change::Profile, out);
                }
            }
            // Jogging ($J=) is not implemented yet.
            [b'J', b'=', ..] => return Err(Error::UnsupportedCommand),
            [b'0'..=b'9', ..] => {
                let mut i = 0;
                let id = gcode::parse_number(cmd, &mut i)?;
                if cmd.get(i) != Some(&b'=') {
                    return Err(Error::InvalidStatement);
                }
                i += 1;
                let value = gcode::parse_number(cmd, &mut i)?;
                if i != cmd.len() || id > 255.0 || id != libm::trunc(id) {
                    return Err(Error::InvalidStatement);
                }
                need_idle(idle)?;
                let change = self.settings.set(id as u16, value, N)?;
                self.settings_changed(change, out);
            }
            _ => return Err(Error::InvalidStatement),
        }
        Ok(())
    }

    /// Follows a settings change through (only ever called while idle); the line's `ok` waits
    /// for the poll that asks for the flash write.
    fn settings_changed(&mut self, change: Change, out: &mut impl Out) {
        if change != Change::None {
            self.start(Job { save: true, ..Job::NONE }, out);
        }
        match change {
            Change::None | Change::Shell => {}
            Change::Pins => self.restart = true,
            Change::Profile => {
                self.limits = Limits::new(&self.settings, self.ramped.cfg.vmax);
                self.apply_profile();
                self.planner.sync(self.shared.positions(), &self.limits);
            }
        }
    }

    /// Writes listing lines while they fit; the listing left, if any.
    pub(super) fn list(&self, mut l: Listing, out: &mut impl Out) -> Option<Listing> {
        loop {
            match l {
                Listing::Settings(i) => {
                    let id = Settings::id(i as usize, N)?;
                    if out.room() < SETTING_LEN + 4 {
                        return Some(l);
                    }
                    let (v, d) = self.settings.get(id, N).unwrap_or((0.0, 0));
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
                    report::param::<N>(out, i as usize);
                    l = Listing::Params(i + 1);
                }
            }
        }
    }
}
