//! The `armhil sim` servers under hostile input, end to end over loopback (issue 21): forged
//! Host/Origin on the web view, a web page's cross-protocol POSTs to the Realman and
//! socketcand ports, a Realman client that never reads, connection storms and idle lockout.
//!
//! Loopback only; every loop is bounded in count and in time, and each test ends in a few
//! seconds. The figures the tests measure are printed (`--nocapture` shows them).

use std::io::{ErrorKind, Read, Write};
use std::net::TcpStream;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use super::support::{free_port, listens, start_sim, Sim, ARMHIL};

const WAIT: Duration = Duration::from_secs(5);

/// `armhil sim realman` on a free TCP port (and a web view if `ui`), once both accept.
fn start_realman(ui: bool, extra: &[&str]) -> (Sim, u16, u16) {
    let port = free_port();
    let ui_port = free_port();
    let mut command = Command::new(ARMHIL);
    command
        .args(["sim", "realman", "--port", &port.to_string()])
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::null());
    if ui {
        command.args(["--ui", &format!("127.0.0.1:{ui_port}")]);
    }
    let mut sim = Sim(command.spawn().expect("armhil sim realman starts"));
    let deadline = Instant::now() + Duration::from_secs(20);
    let ports: &[u16] = if ui { &[port, ui_port] } else { &[port] };
    for p in ports {
        while !listens(("127.0.0.1", *p)) {
            assert!(Instant::now() < deadline, "nothing listens on {p}");
            assert!(
                sim.0.try_wait().ok().flatten().is_none(),
                "the emulator exited early"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }
    (sim, port, ui_port)
}

fn connect(port: u16) -> TcpStream {
    let stream = TcpStream::connect(("127.0.0.1", port)).expect("connect");
    stream.set_read_timeout(Some(WAIT)).unwrap();
    stream.set_write_timeout(Some(WAIT)).unwrap();
    stream
}

/// Send `request` and read until the end of a response head, the server closing, or
/// [`WAIT`].
fn http(port: u16, request: &str) -> String {
    let mut stream = connect(port);
    stream.write_all(request.as_bytes()).unwrap();
    let mut seen = Vec::new();
    let mut buf = [0u8; 4096];
    let deadline = Instant::now() + WAIT;
    while Instant::now() < deadline && !seen.windows(4).any(|w| w == b"\r\n\r\n") {
        match stream.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => seen.extend_from_slice(&buf[..n]),
        }
    }
    String::from_utf8_lossy(&seen).into_owned()
}

/// Whether the server closes `stream` (EOF or reset) within [`WAIT`], reading what it sends.
fn closed_by_server(stream: &mut TcpStream) -> bool {
    let mut buf = [0u8; 4096];
    let deadline = Instant::now() + WAIT;
    while Instant::now() < deadline {
        match stream.read(&mut buf) {
            Ok(0) => return true,
            Ok(_) => {}
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                return false
            }
            Err(_) => return true,
        }
    }
    false
}

/// One Realman request and its reply line (`None`: no reply within [`WAIT`]).
fn ask(stream: &mut TcpStream, request: &str) -> Option<serde_json::Value> {
    stream.write_all(request.as_bytes()).ok()?;
    stream.write_all(b"\r\n").ok()?;
    let mut line = Vec::new();
    let mut byte = [0u8; 1];
    while !line.ends_with(b"\r\n") {
        match stream.read(&mut byte) {
            Ok(1) => line.push(byte[0]),
            _ => return None,
        }
    }
    serde_json::from_slice(&line).ok()
}

fn power_state(port: u16) -> Option<i64> {
    let reply = ask(&mut connect(port), r#"{"command":"get_arm_power_state"}"#)?;
    reply["power_state"].as_i64()
}

/// A browser's `fetch(url, {method: "POST", mode: "no-cors", body})` as it reaches the port.
fn browser_post(port: u16, body: &str) -> String {
    format!(
        "POST / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nConnection: keep-alive\r\n\
         Content-Length: {}\r\nOrigin: https://attacker.example\r\n\
         Content-Type: text/plain;charset=UTF-8\r\nAccept: */*\r\n\r\n{body}",
        body.len()
    )
}

/// Resident memory of a process in KiB (Linux).
fn rss_kib(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = status.lines().find(|l| l.starts_with("VmRSS:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Open file descriptors of a process (Linux).
fn fds(pid: u32) -> Option<usize> {
    Some(std::fs::read_dir(format!("/proc/{pid}/fd")).ok()?.count())
}

#[test]
fn the_web_view_answers_only_to_its_own_name() {
    let (_sim, _port, ui) = start_realman(true, &[]);
    let evil = format!("attacker.example:{ui}");
    let upgrade = |host: &str, origin: &str| {
        format!(
            "GET /ws HTTP/1.1\r\nHost: {host}\r\nOrigin: {origin}\r\nConnection: Upgrade\r\n\
             Upgrade: websocket\r\nSec-WebSocket-Version: 13\r\n\
             Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\r\n"
        )
    };
    // DNS rebinding: the page's own name in Host, and a matching Origin.
    for path in ["/", "/state.json", "/hello.json"] {
        let reply = http(
            ui,
            &format!("GET {path} HTTP/1.1\r\nHost: {evil}\r\nOrigin: http://{evil}\r\n\r\n"),
        );
        assert!(reply.starts_with("HTTP/1.1 421"), "{path}: {reply}");
    }
    let reply = http(ui, &upgrade(&evil, &format!("http://{evil}")));
    assert!(reply.starts_with("HTTP/1.1 421"), "ws: {reply}");
    // Another site in the same browser: right Host, foreign Origin.
    let host = format!("127.0.0.1:{ui}");
    let reply = http(ui, &upgrade(&host, "https://attacker.example"));
    assert!(reply.starts_with("HTTP/1.1 403"), "{reply}");
    // The page itself and its WebSocket are served, without a token on loopback.
    let reply = http(
        ui,
        &format!("GET /state.json HTTP/1.1\r\nHost: {host}\r\n\r\n"),
    );
    assert!(reply.starts_with("HTTP/1.1 200"), "{reply}");
    let reply = http(ui, &upgrade(&host, &format!("http://{host}")));
    assert!(reply.starts_with("HTTP/1.1 101"), "{reply}");
}

#[test]
fn a_web_pages_post_to_the_realman_port_does_not_power_the_arm_off() {
    let (_sim, port, _) = start_realman(false, &[]);
    assert_eq!(power_state(port), Some(1));
    let body = r#"{"command":"set_arm_power","arm_power":0}"#;
    let mut page = connect(port);
    page.write_all(browser_post(port, body).as_bytes()).unwrap();
    assert!(
        closed_by_server(&mut page),
        "the HTTP connection stayed open"
    );
    assert_eq!(power_state(port), Some(1), "the page powered the arm off");
    // The same body from a JSON client does (so the test can fail).
    let reply = ask(&mut connect(port), body).expect("a reply");
    assert_eq!(reply["command"], "set_arm_power", "{reply}");
    assert_eq!(power_state(port), Some(0));
}

#[test]
fn a_web_pages_post_to_the_socketcand_port_puts_nothing_on_the_bus() {
    let (_sim, addr) = start_sim(&["piper"]);
    let port: u16 = addr.rsplit(':').next().unwrap().parse().unwrap();
    // An observer in raw mode sees every frame another client puts on the bus.
    let mut observer = connect(port);
    observer.write_all(b"< open can0 >< rawmode >").unwrap();
    let estop = "< open can0 >< send 150 8 01 00 00 00 00 00 00 00 >";
    let mut page = connect(port);
    page.write_all(browser_post(port, estop).as_bytes())
        .unwrap();
    assert!(
        closed_by_server(&mut page),
        "the HTTP connection stayed open"
    );
    let seen_150 = |observer: &mut TcpStream, for_: Duration| {
        observer
            .set_read_timeout(Some(Duration::from_millis(100)))
            .unwrap();
        let mut seen = String::new();
        let mut buf = [0u8; 8192];
        let deadline = Instant::now() + for_;
        while Instant::now() < deadline {
            if let Ok(n) = observer.read(&mut buf) {
                seen.push_str(&String::from_utf8_lossy(&buf[..n]));
                if seen.contains("< frame 150 ") {
                    return true;
                }
                // Keep only a tail: the Piper's feedback is some 1,000 frames a second.
                if seen.len() > 64 * 1024 {
                    seen.drain(..seen.len() - 64);
                }
            }
        }
        false
    };
    assert!(
        !seen_150(&mut observer, Duration::from_millis(700)),
        "the page's e-stop reached the bus"
    );
    // The same elements from a socketcand client do reach it (so the test can fail).
    let mut client = connect(port);
    client.write_all(estop.as_bytes()).unwrap();
    assert!(
        seen_150(&mut observer, WAIT),
        "a client's frame never reached the bus"
    );
    drop(client);
}

#[test]
fn a_realman_client_that_never_reads_has_a_memory_ceiling() {
    let (sim, port, _) = start_realman(false, &["--idle-timeout-s", "0"]);
    let pid = sim.0.id();
    let before = rss_kib(pid);
    let mut stream = connect(port);
    stream
        .set_write_timeout(Some(Duration::from_millis(300)))
        .unwrap();
    let request = br#"{"command":"get_joint_degree"}"#.repeat(2048);
    let mut sent = 0usize;
    let deadline = Instant::now() + Duration::from_secs(6);
    // Up to 64 MiB, for at most 6 s, until the server stops reading.
    while sent < 64 << 20 && Instant::now() < deadline {
        match stream.write(&request) {
            Ok(n) => sent += n,
            Err(_) => break,
        }
    }
    let after = rss_kib(pid);
    eprintln!(
        "non-reading Realman client: {:.1} MiB accepted before the server stopped reading; \
         emulator RSS {before:?} KiB before, {after:?} KiB after",
        sent as f64 / f64::from(1 << 20)
    );
    assert!(
        sent < 32 << 20,
        "the server read {sent} bytes from a client that reads nothing"
    );
    if let (Some(before), Some(after)) = (before, after) {
        assert!(
            after < before + 64 * 1024,
            "RSS grew from {before} KiB to {after} KiB"
        );
    }
    // Other clients are still served.
    assert_eq!(power_state(port), Some(1));
}

#[test]
fn a_connection_storm_on_the_web_view_leaves_the_realman_port_answering() {
    let (sim, port, ui) = start_realman(true, &[]);
    let pid = sim.0.id();
    let base = fds(pid);
    // 300 connections that send half a request and wait (the kernel's backlog takes what
    // the cap does not).
    let mut storm = Vec::new();
    let started = Instant::now();
    for _ in 0..300 {
        if started.elapsed() > Duration::from_secs(5) {
            break;
        }
        match TcpStream::connect_timeout(&([127, 0, 0, 1], ui).into(), Duration::from_secs(1)) {
            Ok(mut s) => {
                let _ = s.write_all(b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n");
                storm.push(s);
            }
            Err(_) => break,
        }
    }
    std::thread::sleep(Duration::from_millis(300));
    let during = fds(pid);
    eprintln!(
        "web view storm: {} connections opened; emulator fds {base:?} before, {during:?} during",
        storm.len()
    );
    if let (Some(base), Some(during)) = (base, during) {
        assert!(
            during <= base + 64 + 8,
            "{during} fds (from {base}) under a storm of {}",
            storm.len()
        );
    }
    assert_eq!(
        power_state(port),
        Some(1),
        "the Realman port stopped answering"
    );
}

#[test]
fn a_socketcand_connection_storm_is_capped() {
    let (sim, addr) = start_sim(&["piper"]);
    let port: u16 = addr.rsplit(':').next().unwrap().parse().unwrap();
    let pid = sim.0.id();
    let base = fds(pid);
    let mut storm = Vec::new();
    let started = Instant::now();
    for _ in 0..250 {
        if started.elapsed() > Duration::from_secs(5) {
            break;
        }
        match TcpStream::connect_timeout(&([127, 0, 0, 1], port).into(), Duration::from_secs(1)) {
            Ok(s) => storm.push(s),
            Err(_) => break,
        }
    }
    std::thread::sleep(Duration::from_millis(300));
    let during = fds(pid);
    // Those over the cap (128) were closed by the server without a `< hi >`.
    let closed = storm
        .iter()
        .filter(|s| {
            let _ = s.set_read_timeout(Some(Duration::from_millis(50)));
            let mut buf = [0u8; 16];
            let mut reader: &TcpStream = s;
            match reader.read(&mut buf) {
                Ok(0) => true,
                Ok(_) => false,
                Err(e) => e.kind() == ErrorKind::ConnectionReset,
            }
        })
        .count();
    assert!(
        closed >= storm.len().saturating_sub(128),
        "{closed} of {} closed with a cap of 128",
        storm.len()
    );
    eprintln!(
        "socketcand storm: {} connections, {closed} closed by the server; fds {base:?} before, \
         {during:?} during",
        storm.len()
    );
    if let (Some(base), Some(during)) = (base, during) {
        assert!(during <= base + 128 + 8, "{during} fds (from {base})");
    }
    // A new client still gets in once the storm is gone.
    drop(storm);
    let deadline = Instant::now() + WAIT;
    loop {
        let mut s = connect(port);
        let mut hi = [0u8; 6];
        if s.read_exact(&mut hi).is_ok() && &hi == b"< hi >" {
            break;
        }
        assert!(Instant::now() < deadline, "no room after the storm");
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn idle_realman_connections_do_not_lock_others_out() {
    let (_sim, port, _) =
        start_realman(false, &["--max-connections", "4", "--idle-timeout-s", "2"]);
    let idle: Vec<TcpStream> = (0..4).map(|_| connect(port)).collect();
    std::thread::sleep(Duration::from_millis(200));
    let mut refused = connect(port);
    assert!(
        closed_by_server(&mut refused),
        "the cap let a fifth client in"
    );
    // Within the idle timeout (and a margin) a new client is served.
    let deadline = Instant::now() + Duration::from_secs(6);
    loop {
        if power_state(port) == Some(1) {
            break;
        }
        assert!(
            Instant::now() < deadline,
            "still locked out by idle clients"
        );
        std::thread::sleep(Duration::from_millis(200));
    }
    drop(idle);
}

/// The soft and hard open-file limits of a live process, from Linux's /proc.
#[cfg(target_os = "linux")]
fn open_file_limits(pid: u32) -> Option<(u64, u64)> {
    let limits = std::fs::read_to_string(format!("/proc/{pid}/limits")).ok()?;
    let line = limits.lines().find(|l| l.starts_with("Max open files"))?;
    let mut numbers = line["Max open files".len()..].split_whitespace();
    let mut next = || -> Option<u64> {
        match numbers.next()? {
            "unlimited" => Some(u64::MAX),
            n => n.parse().ok(),
        }
    };
    Some((next()?, next()?))
}

#[cfg(target_os = "linux")]
#[test]
fn the_servers_raise_a_low_open_file_limit() {
    // Started the way a login shell with `ulimit -n 256` would start it.
    let port = free_port();
    let child = Command::new("sh")
        .args(["-c", r#"ulimit -Sn 256 && exec "$0" "$@""#, ARMHIL])
        .args(["sim", "realman", "--port", &port.to_string()])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("sh starts armhil");
    let sim = Sim(child);
    let deadline = Instant::now() + Duration::from_secs(20);
    while !listens(("127.0.0.1", port)) {
        assert!(Instant::now() < deadline, "nothing listens on {port}");
        std::thread::sleep(Duration::from_millis(50));
    }
    let (soft, hard) = open_file_limits(sim.0.id()).expect("/proc/PID/limits");
    println!("open-file limit after start: soft {soft}, hard {hard} (started at 256)");
    assert!(soft >= 8192.min(hard), "soft limit {soft} (hard {hard})");
    assert!(soft > 256 || hard <= 256, "the limit was not raised");
}
