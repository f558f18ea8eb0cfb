//! Realman IO ports through the wire (issue 20 item 3): kept across a restart in the state
//! file, visible in the push on request.

use std::time::Duration;

use serde_json::{json, Value};
use testkit::emulators::realman::{client, emulator, emulator_with};

#[tokio::test(start_paused = true)]
async fn io_settings_survive_a_restart_through_the_state_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("realman.json");
    let p = path.clone();
    let emu = emulator_with(move |c| c.controller.state_file = Some(p)).await;
    let mut c = client(&emu);
    for request in [
        r#"{"command":"set_IO_mode","IO_Num":3,"IO_mode":1}"#,
        r#"{"command":"set_DO_state","IO_Num":3,"state":1}"#,
        r#"{"command":"set_tool_IO_mode","IO_Num":1,"state":1}"#,
        r#"{"command":"set_tool_DO_state","IO_Num":1,"state":1}"#,
    ] {
        assert_eq!(c.ask(request).await["set_state"], true, "{request}");
    }
    assert_eq!(
        c.ask(r#"{"command":"set_AO_state","IO_Num":4,"voltage":2500}"#)
            .await["state"],
        true
    );
    assert_eq!(
        c.ask(r#"{"command":"set_tool_voltage","voltage_type":2}"#)
            .await["state"],
        true
    );
    c.ask(r#"{"command":"save_device_info_all"}"#).await;
    emu.shutdown().await;

    let p = path.clone();
    let emu = emulator_with(move |c| c.controller.state_file = Some(p)).await;
    let mut c = client(&emu);
    assert_eq!(
        c.ask(r#"{"command":"get_IO_state","IO_Num":3}"#).await,
        json!({"state":"IO_state","IO_Num":3,"IO_Mode":1,"IO_state":1})
    );
    assert_eq!(
        c.ask(r#"{"command":"get_IO_output"}"#).await,
        json!({"state":"IO_output_state","DO":[0,0,1,0],"AO":[0,0,0,2500]})
    );
    assert_eq!(
        c.ask(r#"{"command":"get_tool_IO_state"}"#).await,
        json!({"state":"tool_IO_state","IO_Mode":[1,0],"IO_State":[1,0]})
    );
    assert_eq!(
        c.ask(r#"{"command":"get_tool_voltage"}"#).await["voltage_type"],
        2
    );
    // The file names the IO settings where a reader looks for them.
    let text = std::fs::read_to_string(&path).unwrap();
    let doc: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(doc["params"]["io"]["modes"], json!([0, 0, 1, 0]));
    emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn the_push_carries_the_io_block_only_when_asked() {
    let emu = emulator().await;
    let mut rx = emu.take_datagrams().expect("datagram channel");
    let mut c = client(&emu);
    tokio::time::sleep(Duration::from_millis(20)).await;
    let plain: Value = serde_json::from_str(&rx.recv().await.unwrap().payload).unwrap();
    assert!(
        plain.get("io_state").is_none(),
        "documented keys only by default"
    );

    c.ask(r#"{"command":"set_IO_mode","IO_Num":2,"IO_mode":1}"#)
        .await;
    c.ask(r#"{"command":"set_DO_state","IO_Num":2,"state":1}"#)
        .await;
    let on = c
        .ask(r#"{"command":"set_realtime_push","custom":{"io_state":true}}"#)
        .await;
    assert_eq!(on["state"], true);
    tokio::time::sleep(Duration::from_millis(20)).await;
    while rx.try_recv().is_ok() {}
    let d: Value = serde_json::from_str(&rx.recv().await.unwrap().payload).unwrap();
    assert_eq!(
        d["io_state"],
        json!({"DIO":[0,1,0,0],"IO_Mode":[0,1,0,0],"AO":[0,0,0,0],"voltage_type":3,
               "tool_IO":[0,0],"tool_IO_Mode":[0,0],"tool_voltage_type":3})
    );
    let push = c.ask(r#"{"command":"get_realtime_push"}"#).await;
    assert_eq!(push["custom"]["io_state"], true);
    emu.shutdown().await;
}
