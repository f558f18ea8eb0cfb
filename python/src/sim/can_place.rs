//! Where a CAN emulator under Python control answers: a SocketCAN interface, or a socketcand
//! server in front of a real-time virtual bus.

use std::collections::BTreeMap;
use std::future::Future;
use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::Arc;

use bus::socketcand::SocketcandServer;
use bus::virtual_bus::VirtualBus;
use bus::CanBus;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

use super::emulated::Stop;
use crate::{block_on, sim_runtime};

/// The bus a CAN emulator answers on.
pub(super) struct CanPlace {
    pub(super) node: Arc<dyn CanBus>,
    /// The virtual bus behind the socketcand server (`None` on SocketCAN).
    pub(super) virtual_bus: Option<VirtualBus>,
    server: Option<SocketcandServer>,
    iface: Option<String>,
}

/// A socketcand server on `addr` with a real-time virtual bus, as `armhil sim --socketcand`.
async fn socketcand_place(addr: &str, node_name: &str) -> Result<CanPlace, String> {
    let (bus, server) = SocketcandServer::bind_realtime_bus(addr)
        .await
        .map_err(|e| format!("cannot serve socketcand on {addr}: {e}"))?;
    Ok(CanPlace {
        node: Arc::new(bus.attach(node_name)),
        virtual_bus: Some(bus),
        server: Some(server),
        iface: None,
    })
}

/// The SocketCAN interface `iface`; the error is the bus crate's, which names the interface
/// and says what to do.
fn iface_place(iface: &str, fd: bool) -> Result<CanPlace, String> {
    // The socket registers with the runtime the emulator runs on (this is no runtime thread).
    let _runtime = sim_runtime().enter();
    let node = bus::open_socketcan_for(iface, fd).map_err(|e| e.to_string())?;
    Ok(CanPlace {
        node,
        virtual_bus: None,
        server: None,
        iface: Some(iface.to_string()),
    })
}

/// `iface` when given, else a socketcand server on `socketcand` (a bare port = loopback).
/// `fd`: the device speaks CAN FD, so a SocketCAN node is a CAN FD socket (socketcand
/// carries classic frames only).
pub(super) fn open_place(
    py: Python<'_>,
    iface: Option<&str>,
    socketcand: &str,
    node: &str,
    fd: bool,
) -> PyResult<CanPlace> {
    let r = match iface {
        Some(i) => iface_place(i, fd),
        None => {
            let addr = match socketcand.parse::<u16>() {
                Ok(port) => format!("127.0.0.1:{port}"),
                Err(_) => socketcand.to_string(),
            };
            let node = node.to_string();
            block_on(py, sim_runtime(), async move {
                socketcand_place(&addr, &node).await
            })
        }
    };
    r.map_err(PyRuntimeError::new_err)
}

impl CanPlace {
    pub(super) fn socketcand_addr(&self) -> Option<SocketAddr> {
        self.server.as_ref().map(SocketcandServer::local_addr)
    }

    /// Closes the node and the server.
    pub(super) async fn close(self) {
        self.node.close().await;
        if let Some(s) = self.server {
            s.shutdown().await;
        }
    }

    /// The `params` a driver uses to reach this bus.
    pub(super) fn params(&self) -> BTreeMap<&'static str, String> {
        match (self.socketcand_addr(), &self.iface) {
            (Some(a), _) => BTreeMap::from([
                ("socketcand", a.to_string()),
                ("can_interface", "can0".to_string()),
            ]),
            (None, Some(i)) => BTreeMap::from([("can_interface", i.clone())]),
            (None, None) => BTreeMap::new(),
        }
    }
}

/// What serves a CAN emulator closes after the emulator has stopped.
impl Stop for CanPlace {
    fn stop(self) -> Pin<Box<dyn Future<Output = ()> + Send>> {
        Box::pin(self.close())
    }
}
