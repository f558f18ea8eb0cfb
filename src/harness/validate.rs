//! Layer 2: check a [`RawScenario`] and build the typed [`Scenario`].

use std::time::Duration;

use super::model::*;
use super::raw::*;
use crate::devices;
use crate::scenario::{pos, Ctx, Pos, Res, MAX_NAME_CHARS};

/// Validate a raw scenario.
///
/// The file's `matrix:` comes already checked ([`matrix_shape`]): a file of N variants is
/// parsed and its matrix checked once, then each variant costs what its steps cost, not N
/// more (which made `armhil check` quadratic in the matrix's size).
pub(crate) fn validate_with(
    ctx: &mut Ctx<'_>,
    raw: &RawScenario,
    shape: &Res<Option<MatrixShape>>,
) -> Res<Scenario> {
    let name = match &raw.name {
        Some(name) => {
            let ok = !name.value.is_empty()
                && name.value.len() <= MAX_NAME_CHARS
                && name
                    .value
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'));
            if !ok {
                return Err(ctx.err(
                    pos(name),
                    format!("`name` must be 1 to {MAX_NAME_CHARS} characters and use only letters, digits, '-', '_' and '.' (it names the output folder)"),
                ));
            }
            name.value.clone()
        }
        None => ctx.file.file_stem().map_or_else(
            || "scenario".to_owned(),
            |s| s.to_string_lossy().into_owned(),
        ),
    };
    let mut tags = Vec::new();
    for tag in raw.tags.iter().flatten() {
        if tag.value != "vcan"
            && !tag
                .value
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
        {
            return Err(ctx.err(pos(tag), "tags use letters, digits, '-' and '_'"));
        }
        tags.push(tag.value.clone());
    }
    ctx.matrix = pick_variant(ctx, shape.as_ref().map_err(Clone::clone)?.as_ref())?;
    let variant = ctx.matrix.as_ref().map(|(_, v)| v.clone());
    let name = match &variant {
        Some(v) => format!("{name}@{v}"),
        None => name,
    };
    let bench = bench(ctx, &raw.bench)?;
    ctx.devices = bench
        .devices
        .iter()
        .map(|d| (d.name.clone(), d.kind.name()))
        .collect();
    ctx.parts = bench.devices.iter().map(|d| d.kind.parts()).collect();
    ctx.part_actuators = bench
        .devices
        .iter()
        .map(|d| d.kind.part_actuators())
        .collect();
    ctx.buses = bench.buses.iter().map(|b| b.name.clone()).collect();
    let record = record(ctx, raw.record.as_ref())?;

    if raw.steps.value.is_empty() {
        return Err(ctx.err(
            pos(&raw.steps),
            "`steps` is empty; a scenario needs at least one step",
        ));
    }
    // Step ids first, so that the fault schedule can refer to any step.
    for step in &raw.steps.value {
        let id = step_id(&step.value).map(|s| (s.value.clone(), pos(s)));
        if let Some((id, at)) = &id {
            if ctx.step_ids.iter().flatten().any(|known| known == id) {
                return Err(ctx.err(*at, format!("duplicate step id `{id}`")));
            }
        }
        ctx.step_ids.push(id.map(|(id, _)| id));
    }
    let mut steps = Vec::new();
    for (index, step) in raw.steps.value.iter().enumerate() {
        steps.push(self::step(ctx, index, step)?);
    }
    let mut faults = Vec::new();
    for entry in raw.faults.iter().flatten() {
        faults.push(scheduled_fault(ctx, entry)?);
    }
    let scenario = Scenario {
        name,
        path: ctx.file.to_path_buf(),
        description: raw.description.clone(),
        tags,
        variant,
        bench,
        record,
        faults,
        steps,
    };
    if scenario.has_tag("vcan") {
        let needs = scenario.in_process_requirements();
        if let Some(first) = needs.first() {
            let at = raw
                .tags
                .iter()
                .flatten()
                .find(|t| t.value == "vcan")
                .map_or_else(Pos::default, pos);
            return Err(ctx.err(
                at,
                format!("tagged `vcan` but needs the in-process emulator: {first}"),
            ));
        }
    }
    Ok(scenario)
}

/// A file's `matrix:` once its shape is checked: the parameter, its values, and where they
/// are written (for the errors of a variant that is not among them).
#[derive(Debug, Clone)]
pub(crate) struct MatrixShape {
    key: String,
    /// The values in file order (for messages).
    listed: Vec<String>,
    /// The same values, to look a variant up without a scan.
    values: std::collections::HashSet<String>,
    /// Where `matrix:` and its list are written.
    at: Pos,
    list_at: Pos,
}

/// `matrix: {key: [values]}`: one parameter, each value a run of its own. Checks the shape in
/// one pass over the values (duplicates through a set: the pairwise comparison this replaced
/// was quadratic in the number of values, per variant).
pub(crate) fn matrix_shape(ctx: &Ctx<'_>, raw: Option<&S<RawMatrix>>) -> Res<Option<MatrixShape>> {
    let Some(raw) = raw else {
        return Ok(None);
    };
    let mut entries = raw.value.iter();
    let (key, values) =
        match (entries.next(), entries.next()) {
            (Some(entry), None) => entry,
            _ => return Err(ctx.err(
                pos(raw),
                "`matrix` takes exactly one parameter, e.g. `matrix: {vendor: [piper, realman]}`",
            )),
        };
    if values.value.is_empty() {
        return Err(ctx.err(pos(values), format!("`matrix.{key}` lists no value")));
    }
    let mut seen = std::collections::HashSet::with_capacity(values.value.len());
    for v in &values.value {
        let ok = !v.value.is_empty()
            && v.value
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_'));
        if !ok {
            return Err(ctx.err(
                pos(v),
                "matrix values use letters, digits, '-' and '_' (each names an output folder)",
            ));
        }
        if !seen.insert(v.value.clone()) {
            return Err(ctx.err(pos(v), format!("`{}` is listed twice", v.value)));
        }
    }
    Ok(Some(MatrixShape {
        key: key.clone(),
        listed: values.value.iter().map(|v| v.value.clone()).collect(),
        values: seen,
        at: pos(raw),
        list_at: pos(values),
    }))
}

/// The variant being loaded as `(parameter, value)`: it must be one of the matrix's values,
/// and a file with a matrix must be loaded as one of its variants.
fn pick_variant(ctx: &Ctx<'_>, shape: Option<&MatrixShape>) -> Res<Option<(String, String)>> {
    let Some(shape) = shape else {
        return match &ctx.variant {
            Some(v) => Err(ctx.err(
                Pos::default(),
                format!("variant `{v}` requested, but the file has no `matrix:`"),
            )),
            None => Ok(None),
        };
    };
    let key = &shape.key;
    match &ctx.variant {
        Some(v) if shape.values.contains(v) => Ok(Some((key.clone(), v.clone()))),
        Some(v) => Err(ctx.err(
            shape.list_at,
            format!("variant `{v}` is not in `matrix.{key}` ({})", shape.listed.join(", ")),
        )),
        None => Err(ctx.err(
            shape.at,
            format!(
                "this file runs once per `{key}` ({}); run it as a suite (`armhil run FILE`), which expands the matrix",
                shape.listed.join(", ")
            ),
        )),
    }
}

fn step_id(step: &RawStep) -> Option<&S<String>> {
    match step {
        RawStep::WaitMs(_) => None,
        RawStep::Inject(a) => a.id.as_ref(),
        RawStep::ClearFaults(a) => a.id.as_ref(),
        RawStep::Expect(c) | RawStep::WaitUntil(c) => c.id.as_ref(),
        RawStep::Device(d) => d.id(),
    }
}

fn bench(ctx: &Ctx<'_>, raw: &S<RawBench>) -> Res<Bench> {
    let mut bitrate_bps = 1_000_000;
    let mut interface = None;
    if let Some(bus) = &raw.value.bus {
        if let Some(rate) = &bus.value.bitrate_bps {
            bitrate_bps = bitrate(ctx, rate)?;
        }
        interface = bus.value.interface.as_ref().map(|i| i.value.clone());
    }
    if raw.value.devices.value.is_empty() {
        return Err(ctx.err(
            pos(&raw.value.devices),
            "`devices` is empty; a bench needs at least one device",
        ));
    }
    let mut devices = Vec::new();
    for (name, device) in &raw.value.devices.value {
        if name == "host" {
            return Err(ctx.err(
                pos(device),
                "`host` is reserved for the driver's bus node; pick another device name",
            ));
        }
        let kind = devices::validate_settings(ctx, device)?;
        let uses = kind.buses(pos(device));
        devices.push((
            pos(device),
            uses,
            DeviceSpec {
                name: name.clone(),
                kind,
                buses: Vec::new(),
            },
        ));
    }
    let mut buses = declared_buses(ctx, raw, bitrate_bps)?;
    let declared = !buses.is_empty();
    // Buses a device names but `bench.buses` does not declare are made for it (at the
    // bit rate its settings need, else the bench's), unless the bench declares its buses.
    for (_, uses, device) in &devices {
        for used in uses {
            let Some(name) = used.name.clone() else {
                continue;
            };
            match buses.iter_mut().find(|b| b.name == name) {
                Some(bus) => {
                    // A device running the bus as CAN FD makes it one (classic devices on it
                    // are the device's settings' to refuse).
                    if used.data_bitrate_bps.is_some() {
                        bus.data_bitrate_bps = used.data_bitrate_bps;
                    }
                    if let Some(rate) = used.bitrate_bps.filter(|r| *r != bus.bitrate_bps) {
                        return Err(ctx.err(
                            used.at,
                            format!(
                                "device `{}` needs bus `{name}` at {rate} bit/s; the bench has it at {} bit/s",
                                device.name, bus.bitrate_bps
                            ),
                        ));
                    }
                }
                None if declared => {
                    let names: Vec<&str> = buses.iter().map(|b| b.name.as_str()).collect();
                    return Err(ctx.err(
                        used.at,
                        format!(
                            "device `{}`: no bus `{name}` in `bench.buses` ({}){}",
                            device.name,
                            names.join(", "),
                            crate::scenario::error::suggestion(&name, &names)
                        ),
                    ));
                }
                None => buses.push(BusSpec {
                    name,
                    bitrate_bps: used.bitrate_bps.unwrap_or(bitrate_bps),
                    data_bitrate_bps: used.data_bitrate_bps,
                }),
            }
        }
    }
    if buses.is_empty() {
        buses.push(BusSpec {
            name: DEFAULT_BUS.to_owned(),
            bitrate_bps,
            data_bitrate_bps: None,
        });
    }
    let mut placed = Vec::new();
    for (at, uses, mut device) in devices {
        for used in uses {
            let index = match &used.name {
                Some(name) => buses.iter().position(|b| &b.name == name),
                None if buses.len() == 1 => Some(0),
                None => {
                    let names: Vec<&str> = buses.iter().map(|b| b.name.as_str()).collect();
                    return Err(ctx.err(
                        at,
                        format!(
                            "device `{}`: the bench has buses {}; say which it is on with `bus:`",
                            device.name,
                            names.join(", ")
                        ),
                    ));
                }
            };
            device.buses.extend(index);
        }
        placed.push(device);
    }
    Ok(Bench {
        buses,
        interface,
        devices: placed,
    })
}

/// `bench.buses`, in name order.
fn declared_buses(ctx: &Ctx<'_>, raw: &S<RawBench>, default_bps: u32) -> Res<Vec<BusSpec>> {
    let Some(declared) = &raw.value.buses else {
        return Ok(Vec::new());
    };
    if raw
        .value
        .bus
        .as_ref()
        .is_some_and(|b| b.value.interface.is_some())
    {
        return Err(ctx.err(
            pos(declared),
            "`bench.buses` and `bench.bus.interface` do not mix: a run on a real interface has one bus",
        ));
    }
    if declared.value.is_empty() {
        return Err(ctx.err(pos(declared), "`buses` is empty; name at least one bus"));
    }
    let mut buses = Vec::new();
    for (name, bus) in &declared.value {
        let name = ctx.bus_name(&S {
            value: name.clone(),
            referenced: bus.referenced,
            defined: bus.defined,
        })?;
        let bitrate_bps = match &bus.value.bitrate_bps {
            Some(rate) => bitrate(ctx, rate)?,
            None => default_bps,
        };
        buses.push(BusSpec {
            name,
            bitrate_bps,
            data_bitrate_bps: None,
        });
    }
    Ok(buses)
}

/// A classic CAN bit rate.
fn bitrate(ctx: &Ctx<'_>, rate: &S<i64>) -> Res<u32> {
    if !(10_000..=1_000_000).contains(&rate.value) {
        return Err(ctx.err(
            pos(rate),
            format!(
                "`bitrate_bps` must be 10000..=1000000 (classic CAN), got {}",
                rate.value
            ),
        ));
    }
    Ok(rate.value as u32)
}

fn record(ctx: &Ctx<'_>, raw: Option<&S<RawRecord>>) -> Res<Record> {
    let mut record = Record {
        sample_period: Duration::from_millis(50),
        signals: vec![Signal::Joints, Signal::Currents, Signal::Gripper],
        candump: true,
        pcap: true,
        plot: true,
    };
    let Some(raw) = raw else {
        return Ok(record);
    };
    if let Some(period) = &raw.value.sample_period_ms {
        let p = ctx.positive_millis(period, "sample_period_ms")?;
        if p < Duration::from_millis(5) {
            return Err(ctx.err(
                pos(period),
                "`sample_period_ms` must be >= 5 (the feedback period)",
            ));
        }
        record.sample_period = p;
    }
    if let Some(signals) = &raw.value.signals {
        record.signals.clear();
        for s in signals {
            let signal = ctx.choice(s, "signals", &Signal::ALL)?;
            if !record.signals.contains(&signal) {
                record.signals.push(signal);
            }
        }
        record.signals.sort();
    }
    record.candump = raw.value.candump.unwrap_or(true);
    record.pcap = raw.value.pcap.unwrap_or(true);
    record.plot = raw.value.plot.unwrap_or(true);
    Ok(record)
}

fn scheduled_fault(ctx: &Ctx<'_>, raw: &S<RawFaultEntry>) -> Res<ScheduledFault> {
    let e = &raw.value;
    let trigger = match (&e.at_ms, &e.after) {
        (Some(at), None) => {
            if let Some(delay) = &e.delay_ms {
                return Err(ctx.err(
                    pos(delay),
                    "`delay_ms` goes with `after:`; with `at_ms` add the delay to the time",
                ));
            }
            FaultTrigger::At(ctx.millis(at, "at_ms")?)
        }
        (None, Some(after)) => {
            let step = ctx
                .step_ids
                .iter()
                .position(|id| id.as_deref() == Some(after.value.as_str()))
                .ok_or_else(|| {
                    let known: Vec<&str> =
                        ctx.step_ids.iter().flatten().map(String::as_str).collect();
                    ctx.err(
                        pos(after),
                        format!(
                            "`after`: no step has id `{}` (step ids: {})",
                            after.value,
                            if known.is_empty() {
                                "none".to_owned()
                            } else {
                                known.join(", ")
                            }
                        ),
                    )
                })?;
            let delay = match &e.delay_ms {
                Some(d) => ctx.millis(d, "delay_ms")?,
                None => Duration::ZERO,
            };
            FaultTrigger::AfterStep { step, delay }
        }
        _ => {
            return Err(ctx.err(
                pos(raw),
                "a scheduled fault needs exactly one of `at_ms: <time>` or `after: <step id>`",
            ))
        }
    };
    let duration = duration(ctx, &e.duration_ms)?;
    let fault = fault(ctx, &e.fault, &e.device, &e.bus, pos(raw))?;
    check_duration(ctx, &fault, duration, pos(raw))?;
    Ok(ScheduledFault {
        line: pos(raw).line,
        trigger,
        duration,
        fault,
    })
}

fn duration(ctx: &Ctx<'_>, raw: &Option<S<i64>>) -> Res<Option<Duration>> {
    raw.as_ref()
        .map(|d| ctx.positive_millis(d, "duration_ms"))
        .transpose()
}

fn check_duration(
    ctx: &Ctx<'_>,
    fault: &FaultSpec,
    duration: Option<Duration>,
    at: Pos,
) -> Res<()> {
    if matches!(
        fault,
        FaultSpec::Bus {
            fault: BusFault::BusOff { .. },
            ..
        }
    ) && duration.is_none()
    {
        return Err(ctx.err(
            at,
            "`bus_off` needs `duration_ms` (the node recovers after it)",
        ));
    }
    Ok(())
}

/// The bench bus a bus fault acts on: the one named, or the bench's only bus.
fn which_bus(ctx: &Ctx<'_>, name: &Option<S<String>>, at: Pos) -> Res<usize> {
    match name {
        Some(name) => ctx
            .buses
            .iter()
            .position(|b| *b == name.value)
            .ok_or_else(|| {
                let names: Vec<&str> = ctx.buses.iter().map(String::as_str).collect();
                ctx.err(
                    pos(name),
                    format!(
                        "no bus `{}` on this bench (buses: {}){}",
                        name.value,
                        names.join(", "),
                        crate::scenario::error::suggestion(&name.value, &names)
                    ),
                )
            }),
        None if ctx.buses.len() <= 1 => Ok(0),
        None => Err(ctx.err(
            at,
            format!(
                "the bench has buses {}; say which this fault acts on with `bus:`",
                ctx.buses.join(", ")
            ),
        )),
    }
}

fn node(ctx: &Ctx<'_>, raw: &S<String>) -> Res<String> {
    if raw.value == "host" || ctx.devices.iter().any(|(d, _)| *d == raw.value) {
        Ok(raw.value.clone())
    } else {
        Err(ctx.err(
            pos(raw),
            format!(
                "unknown node `{}`; expected `host` (the driver) or a device: {}",
                raw.value,
                ctx.devices
                    .iter()
                    .map(|(d, _)| d.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ))
    }
}

fn frames(ctx: &Ctx<'_>, sel: &RawFrameSel, at: Pos) -> Res<FrameSelector> {
    match (&sel.id, &sel.node) {
        (Some(_), Some(_)) => Err(ctx.err(at, "select frames by `id` or by `node`, not both")),
        (Some(id), None) => {
            if !(0..=0x7FF).contains(&id.value) {
                return Err(ctx.err(
                    pos(id),
                    format!(
                        "`id` must be a standard 11-bit CAN id (0..=0x7FF), got {}",
                        id.value
                    ),
                ));
            }
            Ok(FrameSelector::Id(id.value as u32))
        }
        (None, Some(n)) => Ok(FrameSelector::Node(node(ctx, n)?)),
        (None, None) => Ok(FrameSelector::All),
    }
}

fn reject_extra(
    ctx: &Ctx<'_>,
    sel: &RawFrameSel,
    kind: &str,
    probability_ok: bool,
    ms_ok: bool,
) -> Res<()> {
    if !probability_ok {
        if let Some(p) = &sel.probability {
            return Err(ctx.err(
                pos(p),
                format!("`probability` only applies to `drop`, not `{kind}`"),
            ));
        }
        if sel.seed.is_some() && sel.probability.is_none() {
            return Err(ctx.err(Pos::default(), "`seed` goes with `probability`"));
        }
    }
    if !ms_ok {
        if let Some(ms) = &sel.ms {
            return Err(ctx.err(
                pos(ms),
                format!("`ms` only applies to `delay`, not `{kind}`"),
            ));
        }
    }
    Ok(())
}

fn fault(
    ctx: &Ctx<'_>,
    raw: &S<RawFault>,
    device: &Option<S<String>>,
    bus_name: &Option<S<String>>,
    at: Pos,
) -> Res<FaultSpec> {
    let fpos = pos(raw);
    let bus = |fault: BusFault| -> Res<FaultSpec> {
        if let Some(d) = device {
            return Err(ctx.err(pos(d), "bus faults act on the bus, not on a device: select frames with `id:` or `node:` instead of `device:`"));
        }
        Ok(FaultSpec::Bus {
            bus: which_bus(ctx, bus_name, at)?,
            fault,
        })
    };
    match &raw.value {
        RawFault::Device(f) => {
            if let Some(b) = bus_name {
                return Err(ctx.err(
                    pos(b),
                    "`bus:` names the bus of a bus fault; a device's fault acts on the device",
                ));
            }
            let known_device = ctx.device(device, at).ok();
            let fault = devices::validate_fault(ctx, f, known_device, fpos)?;
            let device = ctx.device_of_kind(
                device,
                at,
                fault.kind_name(),
                &format!("`{}`", fault.describe()),
            )?;
            Ok(FaultSpec::Emulator { device, fault })
        }
        RawFault::Drop(sel) => {
            reject_extra(ctx, sel, "drop", true, false)?;
            let probability = match &sel.probability {
                Some(p) => {
                    let v = ctx.finite(p, "probability")?;
                    if !(0.0..=1.0).contains(&v) {
                        return Err(
                            ctx.err(pos(p), format!("`probability` must be in 0..=1, got {v}"))
                        );
                    }
                    Some((v, sel.seed.unwrap_or(1)))
                }
                None => None,
            };
            bus(BusFault::Drop {
                frames: frames(ctx, sel, fpos)?,
                probability,
            })
        }
        RawFault::Delay(sel) => {
            reject_extra(ctx, sel, "delay", false, true)?;
            let ms = ctx.required(&sel.ms, "ms", "delay", fpos)?;
            let delay = ctx.positive_millis(ms, "ms")?;
            bus(BusFault::Delay {
                frames: frames(ctx, sel, fpos)?,
                delay,
            })
        }
        RawFault::Corrupt(sel) => {
            reject_extra(ctx, sel, "corrupt", false, false)?;
            bus(BusFault::Corrupt {
                frames: frames(ctx, sel, fpos)?,
            })
        }
        RawFault::Duplicate(sel) => {
            reject_extra(ctx, sel, "duplicate", false, false)?;
            bus(BusFault::Duplicate {
                frames: frames(ctx, sel, fpos)?,
            })
        }
        RawFault::Silence(n) => {
            let n = ctx.required(&n.node, "node", "silence", fpos)?;
            bus(BusFault::Silence {
                node: node(ctx, n)?,
            })
        }
        RawFault::BusOff(n) => {
            let n = ctx.required(&n.node, "node", "bus_off", fpos)?;
            bus(BusFault::BusOff {
                node: node(ctx, n)?,
            })
        }
    }
}

fn step(ctx: &Ctx<'_>, index: usize, raw: &S<RawStep>) -> Res<Step> {
    let at = pos(raw);
    let (label, kind) = step_kind(ctx, &raw.value, at)?;
    Ok(Step {
        index,
        line: at.line,
        id: ctx.step_ids.get(index).cloned().flatten(),
        label: label.to_owned(),
        kind,
    })
}

fn step_kind(ctx: &Ctx<'_>, raw: &RawStep, at: Pos) -> Res<(&'static str, StepKind)> {
    Ok(match raw {
        RawStep::WaitMs(ms) => ("wait_ms", StepKind::Wait(ctx.millis(ms, "wait_ms")?)),
        RawStep::Device(d) => {
            let (label, step) = devices::validate_step(ctx, d, at)?;
            let (name, actual) = &ctx.devices[step.device];
            if *actual != step.action.kind_name() {
                return Err(ctx.err(
                    at,
                    format!(
                        "`{label}` is a {} step, but device `{name}` is a {actual}",
                        step.action.kind_name()
                    ),
                ));
            }
            let kind = StepKind::Action {
                device: step.device,
                action: step.action,
                timeout: step.timeout,
                expect_error: step.expect_error,
            };
            (label, kind)
        }
        RawStep::Inject(a) => {
            let fault = fault(ctx, &a.fault, &a.device, &a.bus, at)?;
            let duration = duration(ctx, &a.duration_ms)?;
            check_duration(ctx, &fault, duration, at)?;
            ("inject", StepKind::Inject { fault, duration })
        }
        RawStep::ClearFaults(a) => (
            "clear_faults",
            StepKind::ClearFaults {
                device: ctx.device(&a.device, at)?,
            },
        ),
        RawStep::Expect(c) => {
            if let Some(t) = &c.timeout_ms {
                return Err(ctx.err(pos(t), "`expect` checks now (or throughout `for_ms`); to wait for a condition use `wait_until` with `timeout_ms`"));
            }
            let hold = c
                .for_ms
                .as_ref()
                .map(|f| ctx.positive_millis(f, "for_ms"))
                .transpose()?;
            let device = ctx.device(&c.device, at)?;
            (
                "expect",
                StepKind::Expect {
                    device,
                    checks: checks(ctx, c, device, "expect", at)?,
                    hold,
                },
            )
        }
        RawStep::WaitUntil(c) => {
            if let Some(f) = &c.for_ms {
                return Err(ctx.err(
                    pos(f),
                    "`for_ms` goes with `expect`; `wait_until` takes `timeout_ms`",
                ));
            }
            let t = ctx.required(&c.timeout_ms, "timeout_ms", "wait_until", at)?;
            let timeout = ctx.positive_millis(t, "timeout_ms")?;
            let device = ctx.device(&c.device, at)?;
            (
                "wait_until",
                StepKind::WaitUntil {
                    device,
                    checks: checks(ctx, c, device, "wait_until", at)?,
                    timeout,
                },
            )
        }
    })
}

fn checks(ctx: &Ctx<'_>, c: &RawConditions, device: usize, step: &str, at: Pos) -> Res<Vec<Check>> {
    let Some(conds) = &c.conds else {
        return Err(ctx.err(
            at,
            format!(
                "`{step}` has no condition (for example `joints_deg`, `arm_status`, `enabled`)"
            ),
        ));
    };
    let checks = devices::validate_checks(ctx, conds, device, step, at)?;
    let (name, actual) = &ctx.devices[device];
    if let Some(other) = checks.iter().find(|c| c.kind_name() != *actual) {
        return Err(ctx.err(
            at,
            format!(
                "`{step}` checks {} conditions, but device `{name}` is a {actual}",
                other.kind_name()
            ),
        ));
    }
    Ok(checks)
}
