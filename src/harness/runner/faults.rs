//! Applying and removing faults at scenario time, with an event log.

use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use bus::virtual_bus::{Fault, FaultHandle, FaultId, FrameFilter};
use bus::CanId;
use tokio::task::JoinHandle;
use tokio::time::Instant;

use crate::devices::Device;
use crate::harness::model::{BusFault, FaultSpec, FrameSelector};
use crate::harness::result::FaultEvent;

/// Applies faults to devices and the bus, and logs every change.
pub(crate) struct FaultControl {
    devices: Vec<Arc<dyn Device>>,
    /// Each virtual bus's name and fault handle, in bench order (none with `--iface`).
    buses: Vec<(String, FaultHandle)>,
    t0: Instant,
    events: Mutex<Vec<FaultEvent>>,
    timers: Mutex<Vec<JoinHandle<()>>>,
    errors: Mutex<Vec<String>>,
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

fn filter(frames: &FrameSelector) -> Result<FrameFilter, String> {
    Ok(match frames {
        FrameSelector::All => FrameFilter::All,
        FrameSelector::Id(id) => {
            let raw = u16::try_from(*id).map_err(|_| format!("id 0x{id:X} is not 11-bit"))?;
            FrameFilter::Id(CanId::standard(raw).map_err(|e| e.to_string())?)
        }
        FrameSelector::Node(node) => FrameFilter::Node(node.clone()),
    })
}

/// What must be undone when a fault's duration ends.
enum Undo {
    Bus(usize, FaultId),
    Emulator(usize),
    /// Bus-off recovers by itself; only the event is logged.
    Nothing,
}

impl FaultControl {
    pub fn new(
        devices: Vec<Arc<dyn Device>>,
        buses: Vec<(String, FaultHandle)>,
        t0: Instant,
    ) -> Self {
        Self {
            devices,
            buses,
            t0,
            events: Mutex::new(Vec::new()),
            timers: Mutex::new(Vec::new()),
            errors: Mutex::new(Vec::new()),
        }
    }

    fn log(&self, action: &'static str, fault: &FaultSpec) {
        let target = match fault {
            FaultSpec::Emulator { device, .. } => self
                .devices
                .get(*device)
                .map_or_else(|| "?".to_owned(), |d| d.name().to_owned()),
            // A bench of one bus says just "bus"; of several, which.
            FaultSpec::Bus { bus, .. } => match (self.buses.len(), self.buses.get(*bus)) {
                (2.., Some((name, _))) => format!("bus {name}"),
                _ => "bus".to_owned(),
            },
        };
        lock(&self.events).push(FaultEvent {
            at: self.t0.elapsed(),
            action,
            fault: fault.describe(),
            target,
        });
    }

    /// Apply `fault` now; when `duration` is set, remove it after that long.
    pub async fn apply(
        self: &Arc<Self>,
        fault: &FaultSpec,
        duration: Option<Duration>,
    ) -> Result<(), String> {
        let undo = match fault {
            FaultSpec::Emulator { device, fault: f } => {
                let dev = self
                    .devices
                    .get(*device)
                    .ok_or_else(|| format!("no device #{device}"))?;
                dev.inject(f).await.map_err(|e| e.to_string())?;
                Undo::Emulator(*device)
            }
            FaultSpec::Bus {
                bus,
                fault: bus_fault,
            } => {
                let bus = *bus;
                let (_, handle) = self.buses.get(bus).ok_or_else(|| {
                    "bus faults need the in-process virtual bus (not available with --iface)"
                        .to_owned()
                })?;
                match bus_fault {
                    BusFault::Drop {
                        frames,
                        probability,
                    } => {
                        let f = filter(frames)?;
                        let fault = match probability {
                            Some((p, seed)) => Fault::drop_with_probability(f, *p, *seed),
                            None => Fault::drop(f),
                        };
                        Undo::Bus(bus, handle.inject(fault))
                    }
                    BusFault::Delay { frames, delay } => {
                        Undo::Bus(bus, handle.inject(Fault::delay(filter(frames)?, *delay)))
                    }
                    BusFault::Corrupt { frames } => {
                        Undo::Bus(bus, handle.inject(Fault::corrupt(filter(frames)?)))
                    }
                    BusFault::Duplicate { frames } => {
                        Undo::Bus(bus, handle.inject(Fault::duplicate(filter(frames)?)))
                    }
                    BusFault::Silence { node } => Undo::Bus(bus, handle.silence_node(node)),
                    BusFault::BusOff { node } => {
                        let Some(duration) = duration else {
                            return Err("bus_off needs a duration".to_owned());
                        };
                        if handle.bus_off(node, duration) == 0 {
                            return Err(format!("no node named `{node}` on the bus"));
                        }
                        Undo::Nothing
                    }
                }
            }
        };
        self.log("inject", fault);
        if let Some(duration) = duration {
            let this = Arc::clone(self);
            let fault = fault.clone();
            let timer = tokio::spawn(async move {
                tokio::time::sleep(duration).await;
                this.undo(undo, &fault).await;
            });
            lock(&self.timers).push(timer);
        }
        Ok(())
    }

    async fn undo(&self, undo: Undo, fault: &FaultSpec) {
        match undo {
            Undo::Bus(bus, id) => {
                if let Some((_, handle)) = self.buses.get(bus) {
                    handle.remove(id);
                }
            }
            Undo::Emulator(device) => {
                if let (Some(dev), FaultSpec::Emulator { fault: f, .. }) =
                    (self.devices.get(device), fault)
                {
                    if let Err(e) = dev.clear(Some(f)).await {
                        lock(&self.errors).push(format!("clearing {}: {e}", f.describe()));
                    }
                }
            }
            Undo::Nothing => {}
        }
        self.log("clear", fault);
    }

    /// Schedule `fault` to start after `delay`.
    pub fn schedule(
        self: &Arc<Self>,
        delay: Duration,
        fault: FaultSpec,
        duration: Option<Duration>,
    ) {
        let this = Arc::clone(self);
        let timer = tokio::spawn(async move {
            tokio::time::sleep(delay).await;
            if let Err(e) = this.apply(&fault, duration).await {
                lock(&this.errors).push(format!("injecting {}: {e}", fault.describe()));
            }
        });
        lock(&self.timers).push(timer);
    }

    /// Remove every emulator fault of `device` and every bus fault.
    pub async fn clear_all(&self, device: usize) -> Result<(), String> {
        if let Some(dev) = self.devices.get(device) {
            dev.clear(None).await.map_err(|e| e.to_string())?;
        }
        for (_, handle) in &self.buses {
            handle.clear();
        }
        lock(&self.events).push(FaultEvent {
            at: self.t0.elapsed(),
            action: "clear",
            fault: "all faults".to_owned(),
            target: self
                .devices
                .get(device)
                .map_or_else(|| "?".to_owned(), |d| d.name().to_owned()),
        });
        Ok(())
    }

    /// Stop pending timers; return the events and the errors of scheduled faults.
    pub fn finish(&self) -> (Vec<FaultEvent>, Vec<String>) {
        for timer in lock(&self.timers).drain(..) {
            timer.abort();
        }
        let events = std::mem::take(&mut *lock(&self.events));
        let errors = std::mem::take(&mut *lock(&self.errors));
        (events, errors)
    }
}
