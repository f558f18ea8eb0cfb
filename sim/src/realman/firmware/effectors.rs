//! End effectors: the EG2-4C2 gripper and the 6-DoF dexterous hand (docs/protocols/realman.md
//! §10). Dimensionless 0–1000 positions moving at a rate set by the commanded speed; a blocking
//! command earns an arrival event (device 1 gripper, 2 hand) when the motion ends.

use super::motion::arrival;
use super::{ClientId, Controller, Event, STEP_S};

/// Position units per second at speed 1000 (full stroke in about 0.8 s).
const FULL_SPEED_UNITS_PER_S: f64 = 1250.0;

/// Gripper `mode` values.
pub mod gripper_mode {
    /// Open at maximum, idle.
    pub const OPEN_IDLE: u8 = 1;
    /// Closed at minimum, idle.
    pub const CLOSED_IDLE: u8 = 2;
    /// Stopped, idle.
    pub const STOPPED_IDLE: u8 = 3;
    /// Closing.
    pub const CLOSING: u8 = 4;
    /// Opening.
    pub const OPENING: u8 = 5;
}

/// The gripper.
#[derive(Debug, Clone, PartialEq)]
pub struct Gripper {
    /// Opening 0–1000.
    pub position: f64,
    /// Where it is going.
    pub target: f64,
    /// Units per second.
    pub rate: f64,
    /// Route (stroke limits) 0–1000.
    pub route: (i64, i64),
    /// Grip force setting.
    pub force: i64,
    /// `mode` (see `gripper_mode`).
    pub mode: u8,
    /// Error bits.
    pub error_bits: u8,
    /// Client owed an arrival event.
    pub waiting: Option<ClientId>,
}

impl Default for Gripper {
    fn default() -> Self {
        Self {
            position: 1000.0,
            target: 1000.0,
            rate: 0.0,
            route: (0, 1000),
            force: 0,
            mode: gripper_mode::OPEN_IDLE,
            error_bits: 0,
            waiting: None,
        }
    }
}

impl Gripper {
    /// Start a motion to `target` at `speed` (1–1000).
    pub fn command(&mut self, target: f64, speed: i64, block: Option<ClientId>) {
        let (lo, hi) = (self.route.0 as f64, self.route.1 as f64);
        self.target = target.clamp(lo, hi);
        self.rate = FULL_SPEED_UNITS_PER_S * (speed.clamp(1, 1000) as f64) / 1000.0;
        self.mode = if self.target < self.position {
            gripper_mode::CLOSING
        } else {
            gripper_mode::OPENING
        };
        self.waiting = block;
    }

    fn tick(&mut self) -> Option<ClientId> {
        if self.mode != gripper_mode::CLOSING && self.mode != gripper_mode::OPENING {
            return None;
        }
        let step = self.rate * STEP_S;
        let delta = (self.target - self.position).clamp(-step, step);
        self.position += delta;
        if (self.target - self.position).abs() > 1e-9 {
            return None;
        }
        self.mode = if self.position <= self.route.0 as f64 {
            gripper_mode::CLOSED_IDLE
        } else if self.position >= self.route.1 as f64 {
            gripper_mode::OPEN_IDLE
        } else {
            gripper_mode::STOPPED_IDLE
        };
        self.waiting.take()
    }
}

/// The dexterous hand (six fingers' positions, 0–1000).
#[derive(Debug, Clone, PartialEq)]
pub struct Hand {
    /// Finger positions.
    pub angles: [f64; 6],
    /// Targets.
    pub targets: [f64; 6],
    /// Speed setting 1–1000.
    pub speed: i64,
    /// Force setting 1–1000.
    pub force: i64,
    /// Client owed an arrival event.
    pub waiting: Option<ClientId>,
}

impl Default for Hand {
    fn default() -> Self {
        Self {
            angles: [1000.0; 6],
            targets: [1000.0; 6],
            speed: 500,
            force: 500,
            waiting: None,
        }
    }
}

impl Hand {
    /// Move every finger whose target is not −1.
    pub fn command(&mut self, targets: &[i64], block: Option<ClientId>) {
        for (slot, t) in self.targets.iter_mut().zip(targets) {
            if *t >= 0 {
                *slot = (*t).min(1000) as f64;
            }
        }
        self.waiting = block;
    }

    fn tick(&mut self) -> Option<ClientId> {
        let step = FULL_SPEED_UNITS_PER_S * self.speed.clamp(1, 1000) as f64 / 1000.0 * STEP_S;
        let mut done = true;
        for (a, t) in self.angles.iter_mut().zip(&self.targets) {
            *a += (t - *a).clamp(-step, step);
            done &= (t - *a).abs() < 1e-9;
        }
        if done {
            self.waiting.take()
        } else {
            None
        }
    }
}

impl Controller {
    pub(super) fn tick_effectors(&mut self) {
        if let Some(client) = self.gripper.as_mut().and_then(Gripper::tick) {
            self.events.push(Event {
                to: client,
                text: arrival(true, 1, 0),
            });
        }
        if let Some(client) = self.hand.tick() {
            self.events.push(Event {
                to: client,
                text: arrival(true, 2, 0),
            });
        }
    }
}
