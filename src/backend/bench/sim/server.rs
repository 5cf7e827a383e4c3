//! The simulated CPU on 127.0.0.1: the scan thread, the listener and a thread per connection.
//! Apart from the program, which knows nothing of sockets, so that every link's server starts
//! and stops a CPU alike.

use std::io::Read;
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use super::cpu::Audit;
use super::fault::FaultRule;
use super::scan::{scan, Program};
use crate::backend::bench::error::LiveError;
use crate::device::Device;

/// A simulated CPU serving on 127.0.0.1; dropping it stops it. `L` is its link's server.
pub struct Running<L> {
    address: SocketAddr,
    program: Arc<Program<L>>,
    threads: Vec<JoinHandle<()>>,
}

impl<L: Send + Sync + 'static> Running<L> {
    /// Starts `program`'s scan thread and a server whose connections `serve` answers.
    pub(crate) fn serve(
        program: Arc<Program<L>>,
        serve: fn(&Program<L>, TcpStream),
    ) -> Result<Running<L>, LiveError> {
        let (address, threads) = program.start(serve)?;
        Ok(Running {
            address,
            program,
            threads,
        })
    }

    /// `127.0.0.1:PORT`.
    pub fn address(&self) -> SocketAddr {
        self.address
    }

    pub fn audit(&self) -> Audit {
        self.program.lock().audit.clone()
    }

    /// Puts the CPU in RUN or STOP.
    pub fn set_running(&self, run: bool) {
        let mut cpu = self.program.lock();
        self.program.set_running(&mut cpu, run);
    }

    /// Adds a fault rule while running.
    pub fn add_fault(&self, rule: FaultRule) {
        self.program.lock().add_fault(rule);
    }

    /// A word of device memory (0 for one the CPU does not have).
    pub fn read(&self, device: &Device) -> u16 {
        self.program.lock().word(device).unwrap_or(0)
    }

    /// Keeps the error flag on whatever the program does, as a CPU on which the program cannot
    /// reset it would.
    pub fn hold_error_flag(&self, held: bool) {
        let flag = self.program.settings.manifest.error.flag.clone();
        self.program.lock().hold(&flag, held);
    }
}

impl<L> Drop for Running<L> {
    fn drop(&mut self) {
        self.program.stop.store(true, Ordering::SeqCst);
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

impl<L> Program<L> {
    /// Starts the scan thread, and a server on 127.0.0.1 (the settings' port) whose every
    /// connection `serve` answers in a thread of its own. The CPU has scanned once before the
    /// port opens, as a CPU in RUN has before anyone can connect to it.
    pub(crate) fn start(
        self: &Arc<Self>,
        serve: fn(&Program<L>, TcpStream),
    ) -> Result<(SocketAddr, Vec<JoinHandle<()>>), LiveError>
    where
        L: Send + Sync + 'static,
    {
        let port = self.settings.port;
        let listener = TcpListener::bind(("127.0.0.1", port))
            .map_err(|e| LiveError::within(format!("cannot listen on 127.0.0.1:{port}"), e))?;
        let address = listener
            .local_addr()
            .map_err(|e| LiveError::within("no local address", e))?;
        listener
            .set_nonblocking(true)
            .map_err(|e| LiveError::within("cannot poll the listener", e))?;
        {
            let mut cpu = self.lock();
            scan(self, &mut cpu);
        }
        let s = self.clone();
        let scanning = std::thread::spawn(move || {
            while !s.stop.load(Ordering::SeqCst) {
                {
                    let mut cpu = s.lock();
                    scan(&s, &mut cpu);
                }
                std::thread::sleep(s.settings.scan);
            }
        });
        let s = self.clone();
        let accepting = std::thread::spawn(move || {
            let mut connections: Vec<JoinHandle<()>> = Vec::new();
            while !s.stop.load(Ordering::SeqCst) {
                match listener.accept() {
                    Ok((stream, _)) => {
                        s.lock().audit.connections += 1;
                        let s = s.clone();
                        connections.push(std::thread::spawn(move || {
                            let _ = stream.set_read_timeout(Some(Duration::from_millis(20)));
                            let _ = stream.set_nodelay(true);
                            serve(&s, stream)
                        }));
                    }
                    Err(_) => std::thread::sleep(Duration::from_millis(2)),
                }
                connections.retain(|c| !c.is_finished());
            }
            for c in connections {
                let _ = c.join();
            }
        });
        Ok((address, vec![scanning, accepting]))
    }

    /// Fills `buf` from `at` on, polling the stop flag; `None` when the connection ends.
    pub(crate) fn fill(&self, stream: &mut TcpStream, buf: &mut [u8], mut at: usize) -> Option<()> {
        while at < buf.len() {
            if self.stop.load(Ordering::SeqCst) {
                return None;
            }
            match stream.read(&mut buf[at..]) {
                Ok(0) => return None,
                Ok(n) => at += n,
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock
                            | std::io::ErrorKind::TimedOut
                            | std::io::ErrorKind::Interrupted
                    ) => {}
                Err(_) => return None,
            }
        }
        Some(())
    }
}
