//! The pseudo-terminal a sender opens as the board's serial port (`/dev/pts/N`, optionally
//! behind a symlink such as `/tmp/ttyBLUEPILL`). For the serve loop.
//!
//! The serve loop keeps the slave side open itself, in raw mode: a sender that closes the port
//! and opens it again finds the same device, and reading the master never fails with EIO
//! between two clients. Baud rate and other settings a sender applies are accepted and ignored
//! (the emulated USART keeps 115200 8N1 timing).

use std::os::fd::{AsFd, OwnedFd};
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use nix::errno::Errno;
use nix::fcntl::{fcntl, FcntlArg, OFlag};
use nix::pty::openpty;
use nix::sys::termios::{cfmakeraw, tcgetattr, tcsetattr, SetArg};

/// The master side (ours), the slave kept open, its path and the symlink we made.
pub struct Pty {
    master: OwnedFd,
    _slave: OwnedFd,
    pub path: PathBuf,
    link: Option<PathBuf>,
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
        let link = match link {
            Some(l) => Some(make_link(l, &path)?),
            None => None,
        };
        Ok(Self { master: pty.master, _slave: pty.slave, path, link })
    }

    // bytes a client wrote, if any (never blocks)
    pub fn read(&self, buf: &mut [u8]) -> Result<usize> {
        match nix::unistd::read(self.master.as_fd(), buf) {
            Ok(n) => Ok(n),
            Err(Errno::EAGAIN) | Err(Errno::EINTR) => Ok(0),
            Err(e) => bail!("reading the pseudo-terminal: {e}"),
        }
    }

    // send bytes to the client; what does not fit (nobody reading, buffer full) is dropped,
    // as a serial line drops what nobody listens to
    pub fn write(&self, mut bytes: &[u8]) {
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
