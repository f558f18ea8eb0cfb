//! Bus figures for the web view: a silent node (or second socket) on the emulator's bus that
//! counts frames per ID and the bus load over the last second.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

use bus::timing::{frame_bits, StuffingPolicy};
use bus::{BusError, CanBus, CanFrame};
use serde_json::{json, Value};

/// Length of the window the load and rates are computed over.
const WINDOW: Duration = Duration::from_secs(1);

/// Counts per ID and bits over the current window.
#[derive(Debug, Default)]
pub struct Figures {
    /// Frames per ID since the tap started.
    totals: BTreeMap<u32, u64>,
    /// Frames per ID in the window being filled.
    window_counts: BTreeMap<u32, u64>,
    window_bits: u64,
    window_start: Option<Instant>,
    /// Frames per second per ID over the last full window.
    rates: BTreeMap<u32, f64>,
    /// Load of the last full window, percent.
    load_percent: Option<f64>,
}

impl Figures {
    /// Count one frame seen at `now` on a bus of `bitrate_bps`.
    pub fn count(&mut self, frame: &CanFrame, now: Instant, bitrate_bps: u32) {
        self.window_start.get_or_insert(now);
        self.roll(now, bitrate_bps);
        let id = frame.raw_id();
        *self.totals.entry(id).or_default() += 1;
        *self.window_counts.entry(id).or_default() += 1;
        self.window_bits += u64::from(frame_bits(frame, StuffingPolicy::Exact));
    }

    /// Close the window being filled if it has lasted `WINDOW` at `now`: its frames give
    /// the rates and the load. Called on every frame and on every read, so that a bus gone
    /// quiet reads 0 instead of the last figures it had. A window is closed within one
    /// `WINDOW` of its first frame (or of the previous close): when it is two windows old,
    /// its frames are all older than the last second, which was silent.
    pub fn roll(&mut self, now: Instant, bitrate_bps: u32) {
        let Some(start) = self.window_start else {
            return;
        };
        let elapsed = now.saturating_duration_since(start);
        if elapsed < WINDOW {
            return;
        }
        if elapsed >= 2 * WINDOW {
            self.rates = self.window_counts.keys().map(|id| (*id, 0.0)).collect();
            self.load_percent = Some(0.0);
        } else {
            let secs = elapsed.as_secs_f64();
            self.rates = self
                .window_counts
                .iter()
                .map(|(id, n)| (*id, *n as f64 / secs))
                .collect();
            self.load_percent =
                Some(100.0 * self.window_bits as f64 / (secs * f64::from(bitrate_bps.max(1))));
        }
        self.window_counts.clear();
        self.window_bits = 0;
        self.window_start = Some(now);
    }

    /// As JSON: `{"load_percent", "ids": [[id hex, total, rate_hz], ...]}`.
    pub fn to_json(&self) -> Value {
        let ids: Vec<Value> = self
            .totals
            .iter()
            .map(|(id, n)| {
                let text = if *id > 0x7FF {
                    format!("{id:08X}")
                } else {
                    format!("{id:03X}")
                };
                json!([text, n, self.rates.get(id).copied().unwrap_or(0.0)])
            })
            .collect();
        json!({"load_percent": self.load_percent, "ids": ids})
    }
}

/// A running tap.
#[derive(Debug, Clone)]
pub struct BusTap {
    figures: Arc<Mutex<Figures>>,
    bitrate_bps: u32,
}

impl BusTap {
    /// Count what `tap` receives (a bus node that never sends) on a bus of `bitrate_bps`.
    pub fn spawn(tap: Arc<dyn CanBus>, bitrate_bps: u32) -> Self {
        let figures = Arc::new(Mutex::new(Figures::default()));
        let shared = Arc::clone(&figures);
        tokio::spawn(async move {
            loop {
                match tap.recv().await {
                    Ok(f) => shared.lock().unwrap_or_else(PoisonError::into_inner).count(
                        &f.frame,
                        Instant::now(),
                        bitrate_bps,
                    ),
                    Err(BusError::Closed) => break,
                    Err(e) => tracing::debug!(error = %e, "web view bus tap"),
                }
            }
        });
        Self {
            figures,
            bitrate_bps,
        }
    }

    /// The figures now, as JSON (the rates and load of the last second: 0 on a quiet bus).
    pub fn to_json(&self) -> Value {
        let mut figures = self.figures.lock().unwrap_or_else(PoisonError::into_inner);
        figures.roll(Instant::now(), self.bitrate_bps);
        figures.to_json()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rates_and_load_come_from_the_last_full_window() {
        let mut f = Figures::default();
        let t0 = Instant::now();
        let frame = CanFrame::standard(0x2A5, &[0; 8]).unwrap();
        let bits = u64::from(frame_bits(&frame, StuffingPolicy::Exact));
        for i in 0..200 {
            f.count(&frame, t0 + Duration::from_millis(5 * i), 1_000_000);
        }
        assert_eq!(f.load_percent, None, "no full window yet");
        f.count(&frame, t0 + Duration::from_millis(1000), 1_000_000);
        let load = f.load_percent.unwrap();
        let want = 100.0 * (200 * bits) as f64 / 1_000_000.0;
        assert!((load - want).abs() < 1e-9, "{load} vs {want}");
        assert!((f.rates[&0x2A5] - 200.0).abs() < 1e-9);
        let json = f.to_json();
        assert_eq!(json["ids"][0][0], "2A5");
        assert_eq!(json["ids"][0][1], 201);
    }

    #[test]
    fn a_bus_gone_quiet_reads_zero_and_keeps_its_totals() {
        let mut f = Figures::default();
        let t0 = Instant::now();
        let frame = CanFrame::standard(0x011, &[0; 8]).unwrap();
        for i in 0..=400 {
            f.count(&frame, t0 + Duration::from_millis(5 * i), 1_000_000);
        }
        // Read while the traffic runs: the last full window's figures.
        f.roll(t0 + Duration::from_millis(2001), 1_000_000);
        assert!((f.rates[&0x011] - 200.0).abs() < 1.0, "{:?}", f.rates);
        assert!(f.load_percent.unwrap() > 1.0);
        // The host stopped at 2 s: the window its last frame opened closes with that frame
        // alone, the next one empty.
        f.roll(t0 + Duration::from_millis(3100), 1_000_000);
        assert!(f.rates[&0x011] < 1.0, "{:?}", f.rates);
        f.roll(t0 + Duration::from_millis(4200), 1_000_000);
        let rate = f.rates.get(&0x011).copied().unwrap_or(0.0);
        assert_eq!((rate, f.load_percent), (0.0, Some(0.0)));
        // Read for the first time long after: a window two seconds old counts for nothing in
        // the last second.
        let mut g = Figures::default();
        for i in 0..100 {
            g.count(&frame, t0 + Duration::from_millis(5 * i), 1_000_000);
        }
        g.roll(t0 + Duration::from_secs(5), 1_000_000);
        assert_eq!((g.rates[&0x011], g.load_percent), (0.0, Some(0.0)));
        let json = g.to_json();
        assert_eq!(
            (&json["ids"][0][1], &json["ids"][0][2]),
            (&json!(100), &json!(0.0))
        );
    }
}
