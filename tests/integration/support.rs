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
    while TcpStream::connect(&addr).is_err() {
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
