//! The in-process emulator of a motor-bus kind (RobStride's, Damiao's) on the bench: the
//! running emulator, what a power cycle (`do: restart`) needs to start it again, and its
//! state folder (the motors' flash: what a `save` step wrote survives a restart), which lives
//! as long as the device. On a real interface there is none ([`BenchEmulator::start`] without
//! a virtual bus): the steps that need it say so.

use std::fmt::Display;
use std::future::Future;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard};

use bus::virtual_bus::VirtualBus;
use bus::CanBus;
use tokio::sync::MappedMutexGuard;

use super::DeviceError;

/// A bus emulator as the bench starts and power-cycles it: one implementation per motor-bus
/// kind, over its `sim` runner.
pub(crate) trait BusEmulator {
    /// Its configuration: the motors, the state file.
    type Config: Clone + Send + Sync;
    /// The running emulator.
    type Handle: Send + Sync;
    /// Why it did not start.
    type Error: Display;
    /// Power the motors on as node `node` of the bus.
    fn power_on(config: Self::Config, node: Arc<dyn CanBus>) -> Result<Self::Handle, Self::Error>;
    /// Power them off (what they saved is on disk already).
    fn power_off(handle: Self::Handle) -> impl Future<Output = ()> + Send;
}

/// What a power cycle needs: the virtual bus, the emulator's node name and configuration.
struct PowerCycle<C> {
    bus: VirtualBus,
    node: String,
    config: C,
}

/// A motor bus's in-process emulator on the bench, or none (a real interface).
pub(crate) struct BenchEmulator<E: BusEmulator> {
    /// How to start it again; `None` without an in-process emulator.
    cycle: Option<PowerCycle<E::Config>>,
    /// The running emulator (none between a failed restart and the next one, or at all).
    handle: tokio::sync::Mutex<Option<E::Handle>>,
    /// The emulator's state folder; dropping it deletes the folder.
    state_dir: Mutex<Option<tempfile::TempDir>>,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // The folder or nothing: consistent whatever panicked.
    m.lock().unwrap_or_else(|p| p.into_inner())
}

impl<E: BusEmulator> BenchEmulator<E> {
    /// Power the emulator of device `name` on as its own node of `bus` (none without a virtual
    /// bus), its state file in a fresh folder named `armhil-{tag}-{name}-…`; `config` makes its
    /// configuration with that file.
    pub(crate) fn start(
        name: &str,
        tag: &str,
        bus: Option<&VirtualBus>,
        config: impl FnOnce(PathBuf) -> E::Config,
    ) -> Result<Self, String> {
        let Some(bus) = bus else {
            return Ok(Self {
                cycle: None,
                handle: tokio::sync::Mutex::new(None),
                state_dir: Mutex::new(None),
            });
        };
        let dir = tempfile::Builder::new()
            .prefix(&format!("armhil-{tag}-{name}-"))
            .tempdir()
            .map_err(|e| format!("device `{name}`: state directory: {e}"))?;
        let config = config(dir.path().join("state.json"));
        let node: Arc<dyn CanBus> = Arc::new(bus.attach(name));
        let handle = E::power_on(config.clone(), node)
            .map_err(|e| format!("device `{name}`: emulator: {e}"))?;
        Ok(Self {
            cycle: Some(PowerCycle {
                bus: bus.clone(),
                node: name.to_owned(),
                config,
            }),
            handle: tokio::sync::Mutex::new(Some(handle)),
            state_dir: Mutex::new(Some(dir)),
        })
    }

    /// The running emulator, held while the guard lives, or why there is none.
    pub(crate) async fn running(&self) -> Result<MappedMutexGuard<'_, E::Handle>, DeviceError> {
        tokio::sync::MutexGuard::try_map(self.handle.lock().await, Option::as_mut).map_err(|_| {
            DeviceError::unsupported(
                "emulator commands need the in-process emulator (not available with --iface)",
            )
        })
    }

    /// `f` of the running emulator, unless there is none or it is in use now.
    pub(crate) fn try_with<R>(&self, f: impl FnOnce(&E::Handle) -> R) -> Option<R> {
        self.handle.try_lock().ok()?.as_ref().map(f)
    }

    /// Power-cycle the emulator: `before` first (what the host lets go of), then off, then on
    /// again from its configuration and state file.
    pub(crate) async fn power_cycle(
        &self,
        before: impl Future<Output = ()>,
    ) -> Result<(), DeviceError> {
        let Some(cycle) = &self.cycle else {
            return Err(DeviceError::unsupported(
                "restart needs the in-process emulator (not available with --iface)",
            ));
        };
        before.await;
        let mut guard = self.handle.lock().await;
        if let Some(old) = guard.take() {
            E::power_off(old).await;
        }
        let node: Arc<dyn CanBus> = Arc::new(cycle.bus.attach(&cycle.node));
        let handle = E::power_on(cycle.config.clone(), node)
            .map_err(|e| DeviceError::unsupported(format!("emulator restart: {e}")))?;
        *guard = Some(handle);
        Ok(())
    }

    /// Power the emulator off for good and delete its state folder (best effort: a leftover
    /// temporary folder is harmless).
    pub(crate) async fn shutdown(&self) {
        if let Some(handle) = self.handle.lock().await.take() {
            E::power_off(handle).await;
        }
        drop(lock(&self.state_dir).take());
    }
}
