//! The TCP port a sender connects to (`--tcp 127.0.0.1:23000`: UGS's TCP connection, bCNC's
//! and pyserial's `socket://host:port`). One client at a time: a new connection replaces the
//! old one, as a sender that reconnects after a network hiccup expects. For the serve loop.

use std::io::{ErrorKind, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};

use anyhow::{Context, Result};

/// The listener and the connected client, if any.
pub struct Tcp {
    listener: TcpListener,
    client: Option<(TcpStream, SocketAddr)>,
    pub addr: SocketAddr,
}

impl Tcp {
    // listen on `addr` ("127.0.0.1:23000"); a bad address or a port in use is an error
    pub fn bind(addr: &str) -> Result<Self> {
        let parsed: SocketAddr = addr
            .parse()
            .with_context(|| format!("--tcp {addr:?} is not an address like 127.0.0.1:23000"))?;
        let listener = TcpListener::bind(parsed).with_context(|| format!("--tcp {addr}: cannot listen there"))?;
        listener.set_nonblocking(true)?;
        let addr = listener.local_addr()?;
        Ok(Self { listener, client: None, addr })
    }

    // accept a waiting connection (replacing the current client); returns its address
    pub fn accept(&mut self) -> Option<SocketAddr> {
        match self.listener.accept() {
            Ok((stream, peer)) => {
                let _ = stream.set_nonblocking(true);
                let _ = stream.set_nodelay(true);
                self.client = Some((stream, peer));
                Some(peer)
            }
            Err(_) => None,
        }
    }

    // the connected client's address
    pub fn peer(&self) -> Option<SocketAddr> {
        self.client.as_ref().map(|c| c.1)
    }

    // bytes the client sent (never blocks); Ok(None) when the client went away
    pub fn read(&mut self, buf: &mut [u8]) -> Option<usize> {
        let (stream, _) = self.client.as_mut()?;
        match stream.read(buf) {
            Ok(0) => {
                self.client = None;
                None
            }
            Ok(n) => Some(n),
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::Interrupted) => Some(0),
            Err(_) => {
                self.client = None;
                None
            }
        }
    }

    // send bytes to the client; a client that cannot take them is dropped
    pub fn write(&mut self, bytes: &[u8]) {
        let Some((stream, _)) = self.client.as_mut() else { return };
        let mut rest = bytes;
        while !rest.is_empty() {
            match stream.write(rest) {
                Ok(0) => break,
                Ok(n) => rest = &rest[n..],
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                // The socket's send buffer is full: the client stopped reading; drop the bytes
                // as a serial line would, keep the client.
                Err(e) if e.kind() == ErrorKind::WouldBlock => return,
                Err(_) => {
                    self.client = None;
                    return;
                }
            }
        }
    }

}
