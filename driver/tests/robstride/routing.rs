//! One driver, two motors on one bus: frames are routed by motor ID, active reports and fault
//! frames update the right handle, and a scan finds who answers.

use std::sync::Arc;
use std::time::Duration;

use bus::virtual_bus::{VirtualBus, VirtualBusConfig, VirtualNode};
use bus::{CanBus, CanFrame};
use driver::robstride::{DriverConfig, FeedbackKind, Model, RobstrideDriver, RobstrideError};

fn status(comm: u32, motor: u32, angle_raw: u16) -> CanFrame {
    let [a, b] = angle_raw.to_be_bytes();
    CanFrame::extended(
        (comm << 24) | (0x80 << 16) | (motor << 8) | 0xFD,
        &[a, b, 0x7F, 0xFF, 0x7F, 0xFF, 0x01, 0x2C],
    )
    .unwrap()
}

/// A fake motor that answers every type-2 poll and ping addressed to it.
async fn fake_motor(node: VirtualNode, id: u32, angle_raw: u16) {
    while let Ok(received) = node.recv().await {
        let raw = received.frame.raw_id();
        if raw & 0xFF != id {
            continue;
        }
        let reply = match raw >> 24 {
            0 => CanFrame::extended((id << 8) | 0xFE, &[id as u8; 8]).unwrap(),
            2 => status(2, id, angle_raw),
            _ => continue,
        };
        if node.send(reply).await.is_err() {
            break;
        }
    }
}

#[tokio::test(start_paused = true)]
async fn replies_reports_and_faults_reach_only_their_motor() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let host: Arc<dyn CanBus> = Arc::new(bus.attach("host"));
    let m1 = bus.attach("m1");
    let m2 = bus.attach("m2");
    let injector = bus.attach("injector");
    tokio::spawn(fake_motor(m1, 1, 0x9000));
    tokio::spawn(fake_motor(m2, 2, 0x7000));
    let driver = RobstrideDriver::new(host, DriverConfig::default());
    let one = driver.motor(1, Model::RS00).unwrap();
    let two = driver.motor(2, Model::RS05).unwrap();

    let (a, b) = tokio::join!(one.poll(), two.poll());
    let (a, b) = (a.unwrap(), b.unwrap());
    assert_eq!((a.motor_id, b.motor_id), (1, 2));
    assert!(a.angle_rad > 0.0 && b.angle_rad < 0.0);
    // RS05 temperature and ranges decode with its own table.
    assert_eq!(b.temperature_c, 30.0);

    // An active report from motor 2 updates only motor 2's feedback.
    injector.send(status(24, 2, 0x8000)).await.unwrap();
    tokio::time::sleep(Duration::from_millis(2)).await;
    assert_eq!(
        two.last_feedback().unwrap().kind,
        FeedbackKind::ActiveReport
    );
    assert_eq!(one.last_feedback().unwrap().kind, FeedbackKind::Reply);

    // A type-21 frame from motor 1.
    let fault = CanFrame::extended(0x1500_01FD, &[0, 0x40, 0, 0, 1, 0, 0, 0]).unwrap();
    injector.send(fault).await.unwrap();
    tokio::time::sleep(Duration::from_millis(2)).await;
    let report = one.last_fault_report().expect("fault routed to motor 1");
    assert!(report.stall_overload() && report.over_temperature_warning());
    assert!(two.last_fault_report().is_none());

    let found = driver.scan(1..=4, Duration::from_millis(5)).await.unwrap();
    assert!(found.is_empty(), "motors with handles are not 'unclaimed'");
    drop(one);
    let found = driver.scan(1..=4, Duration::from_millis(5)).await.unwrap();
    assert_eq!(found, vec![(1, [1; 8])]);
    let three = driver.motor(3, Model::RS03).unwrap();
    assert!(matches!(
        three.poll().await,
        Err(RobstrideError::Timeout { motor: 3, .. })
    ));
}
