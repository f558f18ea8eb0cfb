//! Helpers shared by the tests that start `armhil` processes.

use std::net::TcpStream;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The `armhil` binary under test.
pub const ARMHIL: &str = env!("CARGO_BIN_EXE_armhil");

/// An emulator process, killed when dropped.
pub struct Sim(pub Child);

impl Drop for Sim {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// A TCP port on loopback that was free a moment ago.
pub fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("a free port")
}

/// Whether a server accepts connections on `addr`. A connection whose two ends are the same
/// address is not one: connecting again and again to a free port of the ephemeral range can
/// end in a TCP self-connect, which then holds the port the server is about to bind (it
/// failed to start, and the test talked to itself), so it is dropped and counts as no.
pub fn listens(addr: impl std::net::ToSocketAddrs) -> bool {
    match TcpStream::connect(addr) {
        Ok(stream) => match (stream.local_addr(), stream.peer_addr()) {
            (Ok(local), Ok(peer)) => local != peer,
            _ => false,
        },
        Err(_) => false,
    }
}

/// `armhil sim <args> --socketcand 127.0.0.1:PORT`, once it accepts connections.
pub fn start_sim(args: &[&str]) -> (Sim, String) {
    let addr = format!("127.0.0.1:{}", free_port());
    let child = Command::new(ARMHIL)
        .arg("sim")
        .args(args)
        .args(["--socketcand", &addr])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("armhil sim starts");
    let mut sim = Sim(child);
    let deadline = Instant::now() + Duration::from_secs(20);
    while !listens(&addr) {
        assert!(
            Instant::now() < deadline,
            "emulator never listened on {addr}"
        );
        assert!(
            sim.0.try_wait().ok().flatten().is_none(),
            "emulator exited early"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    (sim, addr)
}
