//! Live Realman state monitor: connects, runs the connect handshake, then prints the UDP state
//! stream.
//!
//! `cargo run -p armhil-driver --example realman_monitor -- --addr 192.168.1.18:8080 --udp 8089`
//! (those are the defaults). With `--aim HOST` the controller is told to push to `HOST:<udp>`
//! at 10 ms with joint speeds and the status string; otherwise it keeps its push settings.
//! Ctrl-C stops.

use std::time::Duration;

use driver::realman::{
    ClientConfig, JointSpeedUnit, PushCustom, PushSettings, RealmanClient, StateFeed,
};

struct Args {
    addr: String,
    udp_port: u16,
    aim: Option<std::net::Ipv4Addr>,
}

fn parse_args() -> Result<Args, String> {
    let mut args = Args {
        addr: "192.168.1.18:8080".into(),
        udp_port: 8089,
        aim: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let value = it.next().ok_or_else(|| format!("{flag} needs a value"))?;
        match flag.as_str() {
            "--addr" => args.addr = value,
            "--udp" => args.udp_port = value.parse().map_err(|e| format!("--udp: {e}"))?,
            "--aim" => args.aim = Some(value.parse().map_err(|e| format!("--aim: {e}"))?),
            other => return Err(format!("unknown option {other} (use --addr, --udp, --aim)")),
        }
    }
    Ok(args)
}

#[tokio::main(flavor = "current_thread")]
async fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = parse_args()?;
    let client = RealmanClient::connect(&args.addr, ClientConfig::default()).await?;
    let h = client.handshake().await?;
    println!(
        "{}: {} ({} joints, controller {:?}), push every {} ms to {}:{} (enabled: {})",
        args.addr,
        h.software.product_version,
        h.software.dof,
        h.software.controller_version,
        h.push.period_ms,
        h.push.ip,
        h.push.port,
        h.push.enable
    );
    if let Some(ip) = args.aim {
        client
            .set_realtime_push(&PushSettings {
                period_ms: 10,
                enable: true,
                port: args.udp_port,
                ip,
                force_coordinate: None,
                custom: PushCustom {
                    joint_speed: Some(true),
                    arm_current_status: Some(true),
                    ..Default::default()
                },
            })
            .await?;
    }
    let feed = StateFeed::bind(
        &format!("0.0.0.0:{}", args.udp_port),
        JointSpeedUnit::default(),
    )
    .await?;
    let mut ticker = tokio::time::interval(Duration::from_millis(500));
    loop {
        tokio::select! {
            _ = tokio::signal::ctrl_c() => break,
            _ = ticker.tick() => {}
        }
        let Some(s) = feed.latest() else {
            println!("no state datagram yet on UDP port {}", args.udp_port);
            continue;
        };
        let joints_deg: Vec<String> = s
            .joints_rad
            .iter()
            .map(|j| format!("{:.2}", j.to_degrees()))
            .collect();
        let p = s.pose.position_m;
        println!(
            "status={:?} joints(deg)=[{}] tcp(m)=({:.4}, {:.4}, {:.4}) currents(A)={:.2?} temps(C)={:.1?} errors={:?} bad datagrams={}",
            s.status,
            joints_deg.join(", "),
            p[0],
            p[1],
            p[2],
            s.currents_a,
            s.temperatures_c,
            s.errors,
            feed.decode_errors()
        );
    }
    Ok(())
}
