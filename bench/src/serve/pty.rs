//! The pseudo-terminal a sender opens as the board's serial port (`/dev/pts/N`, optionally
//! behind a symlink such as `/tmp/ttyBLUEPILL`). For the serve loop.
//!
//! The serve loop keeps the slave side open itself, in raw mode: a sender that closes the port
//! and opens it again finds the same device, and reading the master never fails with EIO
//! between two clients. Baud rate and other settings a sender applies are accepted and ignored
//! (the emulated USART keeps 115200 8N1 timing).
//!
//! New clients start on a quiet line: since the slave stays open, its input queue would keep
//! what a client left unread and hand it to the next one. The slave's opens and closes by
//! clients show up as inotify events on its device node (Linux reports every open and close of
//! a file, device nodes included; the kernel gives a pty master no sign of a slave open while
//! the slave is held open, and termios or packet-mode changes come only from clients that
//! change settings). So the serve loop calls [`Pty::clients`] between reading client bytes and
//! feeding them: when the last client closes, or a client opens after an earlier one, the
//! queue is flushed (`tcflush(TCIFLUSH)` on the slave), and while no client has it open after
//! one has, output is dropped as a serial line drops what nobody listens to. What the board
//! sent before the first client opened (the boot banner) stays for that client.

use std::os::fd::{AsFd, OwnedFd};
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use nix::errno::Errno;
use nix::fcntl::{fcntl, FcntlArg, OFlag};
use nix::pty::openpty;
use nix::sys::inotify::{AddWatchFlags, InitFlags, Inotify};
use nix::sys::termios::{cfmakeraw, tcflush, tcgetattr, tcsetattr, FlushArg, SetArg};

/// The master side (ours), the slave kept open, its path and the symlink we made.
pub struct Pty {
    master: OwnedFd,
    slave: OwnedFd,
    pub path: PathBuf,
    link: Option<PathBuf>,
    /// Opens and closes of the slave's device node (ours came before the watch).
    watch: Inotify,
    /// Clients holding the slave open now, and whether one ever did.
    open: u32,
    had_client: bool,
}

impl Pty {
    // open a pseudo-terminal in raw mode; `link` also makes a symlink to it
    pub fn open(link: Option<&Path>) -> Result<Self> {
        let pty = openpty(None, None).context("cannot create a pseudo-terminal (is /dev/pts mounted, and /dev/ptmx usable?)")?;
        let path = nix::unistd::ttyname(&pty.slave).context("cannot name the pseudo-terminal")?;
        let mut t = tcgetattr(&pty.slave).context("reading the pseudo-terminal's settings")?;
        cfmakeraw(&mut t);
        tcsetattr(&pty.slave, SetArg::TCSANOW, &t).context("setting the pseudo-terminal to raw mode")?;
        fcntl(&pty.master, FcntlArg::F_SETFL(OFlag::O_NONBLOCK)).context("making the pseudo-terminal non-blocking")?;
        let watch = Inotify::init(InitFlags::IN_NONBLOCK | InitFlags::IN_CLOEXEC).context("inotify for the pseudo-terminal's clients")?;
        watch.add_watch(&path, AddWatchFlags::IN_OPEN | AddWatchFlags::IN_CLOSE).context("watching the pseudo-terminal's opens")?;
        let link = match link {
            Some(l) => Some(make_link(l, &path)?),
            None => None,
        };
        Ok(Self { master: pty.master, slave: pty.slave, path, link, watch, open: 0, had_client: false })
    }

    // take note of clients that opened or closed the port since the last call; flush the
    // output queued for the slave when the last one closed or one opened after an earlier
    // one (the serve loop calls this after reading client bytes and before feeding them, so no
    // reply to a new client's bytes is ever flushed); returns whether it flushed
    pub fn clients(&mut self) -> bool {
        let mut flush = false;
        while let Ok(events) = self.watch.read_events() {
            if events.is_empty() {
                break;
            }
            for e in events {
                if e.mask.contains(AddWatchFlags::IN_OPEN) {
                    flush |= self.had_client;
                    self.open += 1;
                    self.had_client = true;
                }
                if e.mask.intersects(AddWatchFlags::IN_CLOSE) {
                    self.open = self.open.saturating_sub(1);
                    flush |= self.open == 0;
                }
            }
        }
        if flush {
            let _ = tcflush(&self.slave, FlushArg::TCIFLUSH);
        }
        flush
    }

    // bytes a client wrote, if any (never blocks)
    pub fn read(&self, buf: &mut [u8]) -> Result<usize> {
        match nix::unistd::read(self.master.as_fd(), buf) {
            Ok(n) => Ok(n),
            Err(Errno::EAGAIN) | Err(Errno::EINTR) => Ok(0),
            Err(e) => bail!("reading the pseudo-terminal: {e}"),
        }
    }

    // send bytes to the client; what does not fit (nobody reading, buffer full), or comes
    // while no client has the port open after one has, is dropped, as a serial line drops what
    // nobody listens to
    pub fn write(&self, mut bytes: &[u8]) {
        if self.had_client && self.open == 0 {
            return;
        }
        while !bytes.is_empty() {
            match nix::unistd::write(self.master.as_fd(), bytes) {
                Ok(0) | Err(_) => return,
                Ok(n) => bytes = &bytes[n..],
            }
        }
    }
}

impl Drop for Pty {
    // remove the symlink we made
    fn drop(&mut self) {
        if let Some(l) = &self.link {
            let _ = std::fs::remove_file(l);
        }
    }
}

// make `link` point at `target`, replacing an old symlink but never a file or directory
fn make_link(link: &Path, target: &Path) -> Result<PathBuf> {
    if let Ok(meta) = std::fs::symlink_metadata(link) {
        if !meta.file_type().is_symlink() {
            bail!("--pty-link {}: exists and is not a symlink; choose another path", link.display());
        }
        std::fs::remove_file(link).with_context(|| format!("--pty-link {}: cannot replace the old symlink", link.display()))?;
    }
    std::os::unix::fs::symlink(target, link).with_context(|| format!("--pty-link {}: cannot create the symlink", link.display()))?;
    Ok(link.to_path_buf())
}
