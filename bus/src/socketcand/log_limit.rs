//! One log line per period for an event that can repeat thousands of times a second.
//!
//! A client that sends megabytes of bad input without reading gets an `< error … >` per
//! element, every one of them dropped from its full queue; a warning per drop turned 3 MB of
//! input into 58 MB of log. [`DropSummary`] turns such a stream into at most one line per
//! period carrying the count since the previous line.

use std::time::Duration;

use tokio::time::Instant;

/// How often a repeated event is logged at most (D10: one summary a second).
pub(crate) const SUMMARY_PERIOD: Duration = Duration::from_secs(1);

/// Counts occurrences of one event and says when to log a summary of them.
///
/// The first occurrence is reported at once (someone watching the log learns of the trouble
/// without waiting); later ones are counted and reported together, at most once per period.
/// What is still counted when the stream stops is taken with [`DropSummary::take`], e.g. when
/// the connection ends.
#[derive(Debug, Clone)]
pub(crate) struct DropSummary {
    period: Duration,
    /// Occurrences not yet reported.
    pending: u64,
    /// All occurrences so far.
    total: u64,
    /// No report before this instant (`None`: nothing reported yet).
    next_report: Option<Instant>,
}

impl DropSummary {
    /// A summary of at most one report per `period`.
    pub(crate) fn new(period: Duration) -> Self {
        Self {
            period,
            pending: 0,
            total: 0,
            next_report: None,
        }
    }

    /// Count one occurrence at `now`. Returns the number to report (the occurrences since the
    /// last report, this one included) when a report is due, else `None`.
    pub(crate) fn record(&mut self, now: Instant) -> Option<u64> {
        self.pending += 1;
        self.total += 1;
        match self.next_report {
            Some(due) if now < due => None,
            _ => {
                self.next_report = Some(now + self.period);
                Some(std::mem::take(&mut self.pending))
            }
        }
    }

    /// The occurrences not reported yet (and forget them), `None` when there are none.
    pub(crate) fn take(&mut self) -> Option<u64> {
        let pending = std::mem::take(&mut self.pending);
        (pending > 0).then_some(pending)
    }

    /// All occurrences counted so far, reported or not.
    pub(crate) fn total(&self) -> u64 {
        self.total
    }
}

impl Default for DropSummary {
    fn default() -> Self {
        Self::new(SUMMARY_PERIOD)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Duration = Duration::from_millis(1);

    #[test]
    fn the_first_occurrence_is_reported_at_once() {
        let mut summary = DropSummary::default();
        assert_eq!(summary.record(Instant::now()), Some(1));
    }

    #[test]
    fn a_flood_gives_one_report_per_period_with_the_count_since_the_last() {
        let start = Instant::now();
        let mut summary = DropSummary::new(1000 * MS);
        let mut reports = Vec::new();
        // 10 000 occurrences a second for 3.5 s: one every 100 µs.
        for i in 0..35_000u32 {
            let now = start + Duration::from_micros(100) * i;
            if let Some(count) = summary.record(now) {
                reports.push((now - start, count));
            }
        }
        let times: Vec<Duration> = reports.iter().map(|(t, _)| *t).collect();
        assert_eq!(times, [Duration::ZERO, 1000 * MS, 2000 * MS, 3000 * MS]);
        let counts: Vec<u64> = reports.iter().map(|(_, n)| *n).collect();
        // The first alone, then a second's worth each (the one at the report instant counted).
        assert_eq!(counts, [1, 10_000, 10_000, 10_000]);
        // What came after the last report is still owed, and nothing is lost or doubled.
        assert_eq!(summary.take(), Some(4_999));
        assert_eq!(summary.take(), None);
        assert_eq!(counts.iter().sum::<u64>() + 4_999, 35_000);
        assert_eq!(summary.total(), 35_000);
    }

    #[test]
    fn sparse_occurrences_are_each_reported() {
        let start = Instant::now();
        let mut summary = DropSummary::new(1000 * MS);
        for i in 0..5u32 {
            assert_eq!(
                summary.record(start + 1500 * MS * i),
                Some(1),
                "occurrence {i}"
            );
        }
        assert_eq!(summary.take(), None);
    }

    #[test]
    fn a_quiet_spell_does_not_bank_reports() {
        let start = Instant::now();
        let mut summary = DropSummary::new(1000 * MS);
        assert_eq!(summary.record(start), Some(1));
        assert_eq!(summary.record(start + 10 * MS), None);
        // Long after: reported at once, with the one held back.
        assert_eq!(summary.record(start + 60_000 * MS), Some(2));
        // And the period starts again from there.
        assert_eq!(summary.record(start + 60_500 * MS), None);
        assert_eq!(summary.record(start + 61_000 * MS), Some(2));
    }
}
