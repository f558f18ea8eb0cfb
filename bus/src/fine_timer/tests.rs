use std::time::Duration;

use tokio::time::Instant;

use super::{FineTimer, VirtualTimeline};
use crate::timing::{bits_duration, frame_bits, StuffingPolicy};
use crate::virtual_bus::{VirtualBus, VirtualBusConfig};
use crate::{CanBus, CanFrame};

fn wire_time(frame: &CanFrame) -> Duration {
    bits_duration(frame_bits(frame, StuffingPolicy::Exact), 1_000_000)
}

fn bus_on(timer: FineTimer) -> VirtualBus {
    VirtualBus::new(VirtualBusConfig {
        timer,
        ..VirtualBusConfig::default()
    })
}

#[tokio::test(start_paused = true)]
async fn on_a_timeline_a_frame_arrives_when_its_last_bit_is_on_the_wire() {
    let guard = VirtualTimeline::start().expect("a paused current-thread runtime");
    let bus = bus_on(FineTimer::Virtual(guard.timeline().clone()));
    let (host, motor) = (bus.attach("host"), bus.attach("motor"));
    let request = CanFrame::extended(0x0300_FD01, &[0; 8]).unwrap();
    let sent = Instant::now();
    host.send(request).await.unwrap();
    let received = motor.recv().await.unwrap();
    let took = Instant::now() - sent;
    assert_eq!(took, wire_time(&request), "not on the next millisecond");
    assert!(took < Duration::from_micros(200), "{took:?}");
    assert_eq!(received.timestamp, took);
}

#[tokio::test(start_paused = true)]
async fn without_a_timeline_the_paused_clock_delivers_on_the_millisecond() {
    // The behaviour the timeline exists to replace, kept for tests that pause the clock alone.
    let bus = bus_on(FineTimer::Auto);
    let (host, motor) = (bus.attach("host"), bus.attach("motor"));
    let sent = Instant::now();
    host.send(CanFrame::extended(0x0300_FD01, &[0; 8]).unwrap())
        .await
        .unwrap();
    motor.recv().await.unwrap();
    assert_eq!(Instant::now() - sent, Duration::from_millis(1));
}

/// A request, a firmware that answers after its turnaround, and the host's view of the round
/// trip: request on the wire, turnaround, answer on the wire — a fraction of a millisecond.
async fn round_trip(turnaround: Duration) -> (Duration, Duration) {
    let guard = VirtualTimeline::start().unwrap();
    let bus = bus_on(FineTimer::Virtual(guard.timeline().clone()));
    let (host, motor) = (bus.attach("host"), bus.attach("motor"));
    let firmware = tokio::spawn(async move {
        let request = motor.recv().await.unwrap();
        let answer = CanFrame::extended(0x0200_01FD, &request.frame.data()[..8]).unwrap();
        motor.send_after(answer, turnaround).await.unwrap();
        motor
    });
    let request = CanFrame::extended(0x0300_FD01, &[7; 8]).unwrap();
    let sent = Instant::now();
    host.send(request).await.unwrap();
    let answer = host.recv().await.unwrap();
    let _motor = firmware.await.unwrap();
    (Instant::now() - sent, answer.timestamp)
}

#[tokio::test(start_paused = true)]
async fn an_answer_leaves_its_turnaround_after_the_request_arrived() {
    let turnaround = Duration::from_micros(120);
    let (host_saw, stamped) = round_trip(turnaround).await;
    let frame = wire_time(&CanFrame::extended(0x0300_FD01, &[7; 8]).unwrap());
    assert_eq!(host_saw, frame + turnaround + frame);
    assert_eq!(stamped, host_saw);
    assert!(host_saw < Duration::from_micros(500), "{host_saw:?}");
    // A longer turnaround is a later answer, to the microsecond.
    let (slower, _) = round_trip(Duration::from_micros(620)).await;
    assert_eq!(slower - host_saw, Duration::from_micros(500));
}

/// A firmware that gets round to a request late (busy with a control step) still answers its
/// turnaround after the request's last bit: the delay it was late is part of the turnaround
/// (`since_received`), not added to it — up to the turnaround, after which it answers at once.
#[tokio::test(start_paused = true)]
async fn a_late_handled_request_is_answered_its_turnaround_after_its_last_bit() {
    for busy_us in [0u64, 70, 300] {
        let guard = VirtualTimeline::start().unwrap();
        let bus = bus_on(FineTimer::Virtual(guard.timeline().clone()));
        let (host, motor) = (bus.attach("host"), bus.attach("motor"));
        let turnaround = Duration::from_micros(120);
        let timeline = guard.timeline().clone();
        let firmware = tokio::spawn(async move {
            let request = motor.recv().await.unwrap();
            let busy = Duration::from_micros(busy_us);
            timeline.sleep_until(Instant::now() + busy).await;
            assert_eq!(motor.since_received(&request), busy);
            let answer = CanFrame::extended(0x0200_01FD, &[7; 8]).unwrap();
            motor
                .send_after(answer, motor.answer_delay(&request, turnaround))
                .await
                .unwrap();
            motor
        });
        let request = CanFrame::extended(0x0300_FD01, &[7; 8]).unwrap();
        host.send(request).await.unwrap();
        let answer = host.recv().await.unwrap();
        let _motor = firmware.await.unwrap();
        let frame = wire_time(&request);
        let expected = frame + turnaround.max(Duration::from_micros(busy_us)) + frame;
        assert_eq!(answer.timestamp, expected, "busy {busy_us} us");
    }
}

/// The wire task sleeps through a turnaround to the end of the answer it expects; a frame
/// queued meanwhile for the same instant with a lower identifier must still win arbitration,
/// and the answer follow it back to back.
#[tokio::test(start_paused = true)]
async fn a_frame_queued_during_a_turnaround_still_arbitrates_against_the_answer() {
    let guard = VirtualTimeline::start().unwrap();
    let bus = bus_on(FineTimer::Virtual(guard.timeline().clone()));
    let (host, motor, other) = (bus.attach("host"), bus.attach("motor"), bus.attach("other"));
    let turnaround = Duration::from_micros(120);
    let request = CanFrame::extended(0x0300_FD01, &[7; 8]).unwrap();
    let answer = CanFrame::extended(0x0200_01FD, &[7; 8]).unwrap();
    let urgent = CanFrame::extended(0x0000_0001, &[1; 8]).unwrap();
    let timeline = guard.timeline().clone();
    let firmware = tokio::spawn(async move {
        motor.recv().await.unwrap();
        motor.send_after(answer, turnaround).await.unwrap();
        // Halfway through the turnaround (the wire task asleep by then), a rival queued for
        // the same instant as the answer.
        let half = turnaround / 2;
        timeline.sleep_until(Instant::now() + half).await;
        other.send_after(urgent, half).await.unwrap();
        (motor, other)
    });
    let sent = Instant::now();
    host.send(request).await.unwrap();
    let first = host.recv().await.unwrap();
    // Received when its last bit left the wire, not when the wire task would have woken.
    assert_eq!(Instant::now() - sent, first.timestamp);
    let second = host.recv().await.unwrap();
    assert_eq!(Instant::now() - sent, second.timestamp);
    let _nodes = firmware.await.unwrap();
    let ready = wire_time(&request) + turnaround;
    assert_eq!(first.frame, urgent);
    assert_eq!(first.timestamp, ready + wire_time(&urgent));
    assert_eq!(second.frame, answer);
    assert_eq!(
        second.timestamp,
        ready + wire_time(&urgent) + wire_time(&answer)
    );
}

#[tokio::test(start_paused = true)]
async fn tokio_timers_keep_their_milliseconds_while_frames_fly() {
    let guard = VirtualTimeline::start().unwrap();
    let bus = bus_on(FineTimer::Virtual(guard.timeline().clone()));
    let (host, motor) = (bus.attach("host"), bus.attach("motor"));
    let start = Instant::now();
    let chatter = tokio::spawn(async move {
        for n in 0..50u8 {
            host.send(CanFrame::standard(0x100, &[n]).unwrap())
                .await
                .unwrap();
            tokio::time::sleep(Duration::from_micros(50)).await;
        }
        host
    });
    let listener = tokio::spawn(async move {
        let mut arrivals = Vec::new();
        for _ in 0..50 {
            arrivals.push(motor.recv().await.unwrap().timestamp);
        }
        arrivals
    });
    let mut ticks = tokio::time::interval(Duration::from_millis(1));
    let mut offsets = Vec::new();
    for _ in 0..20 {
        ticks.tick().await;
        offsets.push(Instant::now() - start);
    }
    let expected: Vec<Duration> = (0..20).map(Duration::from_millis).collect();
    assert_eq!(offsets, expected);
    let _host = chatter.await.unwrap();
    let arrivals = listener.await.unwrap();
    // Sub-millisecond arrivals, not all bunched on boundaries.
    let off_boundary = arrivals
        .iter()
        .filter(|t| t.as_nanos() % 1_000_000 != 0)
        .count();
    assert!(off_boundary > 40, "{arrivals:?}");
}

#[tokio::test(start_paused = true)]
async fn the_same_run_twice_gives_the_same_arrivals() {
    async fn run() -> Vec<(Duration, u8)> {
        let guard = VirtualTimeline::start().unwrap();
        let bus = bus_on(FineTimer::Virtual(guard.timeline().clone()));
        let nodes: Vec<_> = (0..3).map(|n| bus.attach(&format!("n{n}"))).collect();
        let tap = bus.attach("tap");
        for (k, node) in nodes.into_iter().enumerate() {
            tokio::spawn(async move {
                for n in 0..10u8 {
                    let delay = Duration::from_micros(37 * u64::from(n) + 11 * k as u64);
                    node.send_after(CanFrame::standard(0x200 + k as u16, &[n]).unwrap(), delay)
                        .await
                        .unwrap();
                    tokio::time::sleep(Duration::from_micros(300)).await;
                }
                node
            });
        }
        let mut seen = Vec::new();
        for _ in 0..30 {
            let frame = tap.recv().await.unwrap();
            seen.push((frame.timestamp, frame.frame.data()[0]));
        }
        seen
    }
    let first = run().await;
    assert_eq!(first, run().await);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn in_real_time_a_multi_thread_runtime_sleeps_on_a_fine_timer() {
    assert!(
        VirtualTimeline::start().is_none(),
        "no timeline in real time"
    );
    let mut sleeper = FineTimer::Auto.sleeper();
    #[cfg(target_os = "linux")]
    assert!(sleeper.is_fine());
    for micros in [0u64, 150, 400] {
        let deadline = Instant::now() + Duration::from_micros(micros);
        sleeper.sleep_until(deadline).await;
        assert!(Instant::now() >= deadline);
    }
    // A cancelled sleep leaves nothing that ends the next one early.
    let early = Instant::now() + Duration::from_micros(100);
    tokio::select! {
        () = sleeper.sleep_until(Instant::now() + Duration::from_secs(5)) => unreachable!(),
        () = tokio::time::sleep_until(early) => {}
    }
    let deadline = Instant::now() + Duration::from_millis(3);
    sleeper.sleep_until(deadline).await;
    assert!(Instant::now() >= deadline);
}

#[cfg(target_os = "linux")]
#[tokio::test(flavor = "multi_thread", worker_threads = 1)]
async fn a_periodic_timer_counts_what_its_owner_missed() {
    use super::PeriodicTimer;
    let period = Duration::from_millis(2);
    let t0 = std::time::Instant::now();
    let mut timer = PeriodicTimer::new(period).expect("a timerfd");
    // The first expiry at once (more than one if this machine is slow to get here).
    assert!(timer.tick().await.expect("tick") >= 1);
    // An owner busy for three and a half periods: three expiries wait, reported at once.
    std::thread::sleep(Duration::from_micros(7_000));
    assert!(timer.is_overdue());
    let missed = timer.tick().await.expect("tick");
    assert!(missed >= 3, "{missed} expiries");
    // The next one is not early: the 2 ms grid's next point, 8 ms after creation.
    assert!(timer.tick().await.expect("tick") >= 1);
    let since = t0.elapsed();
    assert!(since >= Duration::from_millis(8), "{since:?}");
}

#[cfg(target_os = "linux")]
mod wake_lateness {
    use std::time::Duration;

    use super::super::timerfd::WakeLateness;

    fn learnt_from(samples: impl IntoIterator<Item = Duration>) -> Duration {
        let mut lateness = WakeLateness::default();
        for late in samples {
            lateness.observe(late);
        }
        lateness.advance()
    }

    #[test]
    fn it_settles_on_a_low_quantile_of_what_the_timer_loses() {
        // Wake-ups 30 to 48 µs late (a host's slack), one in five 2 ms (a busy worker, a
        // stall): the 10th percentile is about 32 µs, not the median of 38 or the mean.
        let mut pattern: Vec<Duration> = (0..40u64)
            .map(|n| Duration::from_micros(30 + (n * 7) % 19))
            .collect();
        pattern.extend(std::iter::repeat_n(Duration::from_millis(2), 10));
        let advance = learnt_from(pattern.iter().copied().cycle().take(20_000));
        assert!(
            advance >= Duration::from_micros(29) && advance <= Duration::from_micros(36),
            "{advance:?}"
        );
    }

    #[test]
    fn a_punctual_timer_is_armed_on_time() {
        let advance = learnt_from(std::iter::repeat_n(Duration::from_micros(2), 1_000));
        assert!(advance <= Duration::from_micros(2), "{advance:?}");
        assert_eq!(learnt_from([Duration::ZERO; 100]), Duration::ZERO);
    }

    #[test]
    fn a_timer_far_off_never_makes_a_sleep_spin_longer_than_the_bound() {
        let advance = learnt_from(std::iter::repeat_n(Duration::from_millis(3), 10_000));
        assert_eq!(advance, WakeLateness::MAX_ADVANCE);
    }

    #[test]
    fn one_stall_moves_the_estimate_by_one_step() {
        let settled = learnt_from(std::iter::repeat_n(Duration::from_micros(50), 500));
        let mut lateness = WakeLateness::default();
        for _ in 0..500 {
            lateness.observe(Duration::from_micros(50));
        }
        lateness.observe(Duration::from_millis(5));
        assert!(lateness.advance() <= settled + WakeLateness::STEP_UP);
    }
}

/// The timer armed early never ends a sleep early: every sleep ends at or after its
/// deadline, and by a spin of at most the bound (so, here, well before a millisecond).
#[cfg(target_os = "linux")]
#[tokio::test(flavor = "multi_thread", worker_threads = 1)]
async fn a_sleep_armed_early_still_ends_at_its_deadline() {
    let mut sleeper = FineTimer::Auto.sleeper();
    assert!(sleeper.is_fine());
    let mut worst = Duration::ZERO;
    for n in 0..400u64 {
        let deadline = Instant::now() + Duration::from_micros(100 + (n % 7) * 30);
        sleeper.sleep_until(deadline).await;
        let now = Instant::now();
        assert!(
            now >= deadline,
            "sleep {n} ended {:?} early",
            deadline - now
        );
        worst = worst.max(now - deadline);
    }
    // Printed, not judged: how late this machine's wake-ups stay after the advance.
    println!("latest wake-up after its deadline: {worst:?}");
}
