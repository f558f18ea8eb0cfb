//! The motion queue: planned moves (with `trajectory_connect` groups), pause/continue/stop as
//! a ramp of the path speed, teach jogs and streamed (passthrough) targets.

use std::collections::VecDeque;

use super::super::faults::codes;
use super::super::kinematics::{self, Pose};
use super::super::model::ArmModel;
use super::super::planner::{self, CartesianLimits, PlanError, Trajectory};
use super::super::wire::Obj;
use super::stream::{JointLimits, Stream, Tracking, STREAM_IDLE_MS};
use super::{ClientId, Controller, Event, STEP_S};

/// Path-speed change per second when pausing / continuing (full speed to rest in 0.2 s).
const PAUSE_RAMP_PER_S: f64 = 5.0;
/// Quick stop (`set_arm_stop`): rest in 50 ms.
const STOP_RAMP_PER_S: f64 = 20.0;
/// Slow stop (`set_arm_slow_stop`): rest in 0.5 s.
const SLOW_STOP_RAMP_PER_S: f64 = 2.0;
/// A move has arrived when every joint is this close to its end point, rad (0.01°).
const ARRIVED_TOLERANCE_RAD: f64 = 1.75e-4;
/// Longest wait for the arm to settle after the path's end, ms.
const SETTLE_TIMEOUT_MS: u32 = 300;

/// What a move aims at.
#[derive(Debug, Clone, PartialEq)]
pub enum Goal {
    /// Joint positions, rad.
    Joint(Vec<f64>),
    /// Straight line to a pose.
    Linear(Pose),
    /// Arc through `via` to `to`, `loops` full turns first.
    Circle {
        /// Via point.
        via: Pose,
        /// End point.
        to: Pose,
        /// Extra full circles.
        loops: u32,
    },
    /// Spline through the points.
    Spline(Vec<Pose>),
}

/// Trajectory type reported by `get_arm_current_trajectory`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TrajectoryType {
    /// At rest.
    None,
    /// Joint-space move (data = joints).
    MoveJ,
    /// Linear move (data = pose).
    MoveL,
    /// Arc (data = pose).
    MoveC,
    /// Spline (data = pose).
    MoveS,
}

impl TrajectoryType {
    /// Wire name.
    pub fn wire(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::MoveJ => "movej",
            Self::MoveL => "movel",
            Self::MoveC => "movec",
            Self::MoveS => "moves",
        }
    }

    /// `arm_current_status` string while this runs.
    pub fn status(self) -> &'static str {
        match self {
            Self::None => "idle",
            Self::MoveJ => "move_J",
            Self::MoveL => "move_L",
            Self::MoveC => "move_C",
            Self::MoveS => "move_S",
        }
    }

    /// Whether the reported data is a pose (else joints).
    pub fn reports_pose(self) -> bool {
        matches!(self, Self::MoveL | Self::MoveC | Self::MoveS)
    }
}

/// One accepted motion command.
#[derive(Debug, Clone)]
struct Part {
    goal: Goal,
    speed_percent: f64,
    /// Blend radius toward the next part of its group, % (0 = stop in between).
    blend_r: f64,
    kind: TrajectoryType,
    client: Option<ClientId>,
    /// Arrival events owed when it ends (a spline stands for all its `moves` commands).
    events: u32,
    /// Where it ends, rad (planned at acceptance; the start of the next one).
    end_rad: Vec<f64>,
}

/// A group of parts planned together (one part unless `trajectory_connect` joined several):
/// one blended trajectory, with an arrival event as each part ends.
#[derive(Debug, Clone)]
struct Run {
    parts: Vec<Part>,
    traj: Option<Trajectory>,
    /// When each part ends on the trajectory, s.
    part_ends_s: Vec<f64>,
    /// Parts whose events have been sent.
    done_parts: usize,
    t_s: f64,
    settle_ms: u32,
}

impl Run {
    fn current_part(&self) -> Option<&Part> {
        self.parts.get(self.done_parts).or(self.parts.last())
    }
}

/// What happens when the path speed reaches zero.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
enum AtRest {
    #[default]
    Nothing,
    /// Stay paused.
    Pause,
    /// Drop every move (stop / slow stop).
    Discard,
}

/// A teach jog (`set_*_teach`): moves until `set_stop_teach` or a limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Jog {
    /// One joint (index), direction ±1, speed rad/s.
    Joint {
        /// Joint index.
        joint: usize,
        /// Signed speed, rad/s.
        speed_rad_s: f64,
    },
    /// Along a base axis (0..3 = x,y,z), signed speed m/s.
    Position {
        /// Axis 0..3.
        axis: usize,
        /// Signed speed, m/s.
        speed_m_s: f64,
    },
    /// About a base axis, signed speed rad/s.
    Orientation {
        /// Axis 0..3.
        axis: usize,
        /// Signed speed, rad/s.
        speed_rad_s: f64,
    },
}

/// The queue and its modifiers.
#[derive(Debug, Clone)]
pub struct Motion {
    queue: VecDeque<Run>,
    pending: Vec<Part>,
    scale: f64,
    scale_target: f64,
    ramp_per_s: f64,
    at_rest: AtRest,
    stop_label: Option<&'static str>,
    jog: Option<Jog>,
    stream: Option<Stream>,
}

impl Default for Motion {
    fn default() -> Self {
        Self {
            queue: VecDeque::new(),
            pending: Vec::new(),
            scale: 1.0,
            scale_target: 1.0,
            ramp_per_s: PAUSE_RAMP_PER_S,
            at_rest: AtRest::Nothing,
            stop_label: None,
            jog: None,
            stream: None,
        }
    }
}

impl Motion {
    /// The running move's type (`None` at rest, also while jogging or streaming).
    pub fn current_type(&self) -> TrajectoryType {
        self.queue
            .front()
            .and_then(Run::current_part)
            .map_or(TrajectoryType::None, |p| p.kind)
    }

    /// `arm_current_status` string.
    pub fn status(&self) -> &'static str {
        if let Some(label) = self.stop_label {
            return label;
        }
        if self.at_rest == AtRest::Pause {
            return "pause";
        }
        if let Some(s) = &self.stream {
            return s.status;
        }
        self.current_type().status()
    }

    /// Moves accepted and not finished (queued + waiting for a `trajectory_connect` 0).
    pub fn plan_count(&self) -> usize {
        self.queue.iter().map(|r| r.parts.len()).sum::<usize>() + self.pending.len()
    }

    /// Whether the arm is paused.
    pub fn paused(&self) -> bool {
        self.at_rest == AtRest::Pause
    }

    pub(super) fn forget_client(&mut self, client: ClientId) {
        let queued = self.queue.iter_mut().flat_map(|r| r.parts.iter_mut());
        for part in queued.chain(self.pending.iter_mut()) {
            if part.client == Some(client) {
                part.client = None;
            }
        }
    }

    pub(super) fn set_jog(&mut self, jog: Option<Jog>) {
        self.jog = jog;
    }

    pub(super) fn set_stream(
        &mut self,
        target_rad: Vec<f64>,
        status: &'static str,
        tracking: Tracking,
    ) {
        let stream = Stream::new(target_rad, status, tracking, self.stream.as_ref());
        self.stream = Some(stream);
    }

    /// Whether a planned move or jog is running (streaming does not count).
    pub fn busy(&self) -> bool {
        !self.queue.is_empty() || self.jog.is_some()
    }
}

/// A refused motion: the error code to report.
pub(super) type Refusal = u16;

/// A planned-motion command as the controller accepts it.
#[derive(Debug, Clone)]
pub(super) struct MoveCommand {
    /// Target.
    pub goal: Goal,
    /// Reported trajectory type.
    pub kind: TrajectoryType,
    /// Speed, % of the limits.
    pub speed_percent: f64,
    /// Blend radius toward the next connected move, %.
    pub blend_r: f64,
    /// `trajectory_connect` 1: wait for the group's 0.
    pub connect: bool,
}

impl Controller {
    fn cartesian_limits(&self) -> CartesianLimits {
        CartesianLimits {
            line_speed_m_s: self.params.line_speed_m_s,
            line_acc_m_s2: self.params.line_acc_m_s2,
            angular_speed_rad_s: self.params.angular_speed_rad_s,
            angular_acc_rad_s2: self.params.angular_acc_rad_s2,
        }
    }

    /// The joint index and value of the first joint outside its limits, if any.
    pub(super) fn beyond_limits(&self, joints_rad: &[f64]) -> Option<usize> {
        joints_rad.iter().enumerate().position(|(j, q)| {
            let deg = q.to_degrees();
            !deg.is_finite()
                || deg < self.params.min_deg[j] - 1e-6
                || deg > self.params.max_deg[j] + 1e-6
        })
    }

    /// Joints reaching `pose` from `seed`, or the error code.
    pub(super) fn solve(&self, pose: &Pose, seed: &[f64]) -> Result<Vec<f64>, Refusal> {
        let q = kinematics::inverse(&self.model, pose, seed).map_err(|e| match e {
            kinematics::IkError::OutOfLimits { .. } => codes::BEYOND_JOINT_LIMIT,
            _ => codes::UNREACHABLE,
        })?;
        match self.beyond_limits(&q) {
            Some(_) => Err(codes::BEYOND_JOINT_LIMIT),
            None => Ok(q),
        }
    }

    /// The model as the planner should see it: the controller's current joint limits, speed
    /// and acceleration tables (`set_joint_max_speed` and friends, docs/protocols/realman.md
    /// §9) instead of the factory values.
    fn planning_model(&self) -> ArmModel {
        let mut model = self.model.clone();
        model.joint_min_deg.clone_from(&self.params.min_deg);
        model.joint_max_deg.clone_from(&self.params.max_deg);
        model
            .max_speed_deg_s
            .clone_from(&self.params.max_speed_deg_s);
        model.max_acc_deg_s2.clone_from(&self.params.max_acc_deg_s2);
        model
    }

    fn plan(&self, from: &[f64], goal: &Goal, speed_percent: f64) -> Result<Trajectory, Refusal> {
        let limits = self.cartesian_limits();
        let model = &self.planning_model();
        let result = match goal {
            Goal::Joint(to) => {
                if self.beyond_limits(to).is_some() {
                    return Err(codes::BEYOND_JOINT_LIMIT);
                }
                planner::plan_joint(model, from, to, speed_percent)
            }
            Goal::Linear(to) => planner::plan_linear(model, from, to, speed_percent, &limits),
            Goal::Circle { via, to, loops } => {
                planner::plan_circle(model, from, via, to, speed_percent, *loops, &limits)
            }
            Goal::Spline(points) => {
                planner::plan_spline(model, from, points, speed_percent, &limits)
            }
        };
        let traj = result.map_err(|e| {
            tracing::debug!(error = %e, "Realman motion refused by the planner");
            refusal_code(&e)
        })?;
        // The planner knows the model's limits; the controller's may have been narrowed.
        if self
            .beyond_limits(&traj.sample(traj.duration_s()))
            .is_some()
        {
            return Err(codes::BEYOND_JOINT_LIMIT);
        }
        Ok(traj)
    }

    /// Where the last accepted move ends (the start of the next one).
    pub(super) fn tail_rad(&self) -> Vec<f64> {
        self.motion
            .pending
            .last()
            .or(self.motion.queue.back().and_then(|r| r.parts.last()))
            .map_or_else(|| self.setpoint_rad.clone(), |p| p.end_rad.clone())
    }

    /// Accept or refuse a move. `connect` = `trajectory_connect` 1: plan it together with the
    /// following moves and start only when a 0 arrives.
    pub(super) fn submit(&mut self, client: ClientId, cmd: MoveCommand) -> Result<(), Refusal> {
        let MoveCommand {
            goal,
            kind,
            speed_percent,
            blend_r,
            connect,
        } = cmd;
        if !self.can_move() {
            return Err(if self.power_on {
                codes::JOINT_DISABLED
            } else {
                0
            });
        }
        let from = self.tail_rad();
        let end_rad = match &goal {
            // Spline points are planned together when the group's last point arrives.
            Goal::Spline(_) if connect => from,
            Goal::Spline(last) => {
                let mut points: Vec<Pose> = self
                    .motion
                    .pending
                    .iter()
                    .filter_map(|s| match &s.goal {
                        Goal::Spline(p) => Some(p.iter().copied()),
                        _ => None,
                    })
                    .flatten()
                    .collect();
                points.extend(last.iter().copied());
                let limits = self.cartesian_limits();
                let planned = planner::plan_spline(
                    &self.planning_model(),
                    &from,
                    &points,
                    speed_percent,
                    &limits,
                );
                match planned {
                    Ok(traj) => traj.sample(traj.duration_s()),
                    Err(e) => {
                        tracing::debug!(error = %e, "Realman spline refused by the planner");
                        self.motion
                            .pending
                            .retain(|s| !matches!(s.goal, Goal::Spline(_)));
                        return Err(refusal_code(&e));
                    }
                }
            }
            _ => {
                let traj = self.plan(&from, &goal, speed_percent)?;
                traj.sample(traj.duration_s())
            }
        };
        self.errors.planning = None;
        self.motion.jog = None;
        self.motion.stream = None;
        self.motion.pending.push(Part {
            goal,
            speed_percent,
            blend_r,
            kind,
            client: Some(client),
            events: 1,
            end_rad,
        });
        if !connect {
            self.commit_group();
        }
        Ok(())
    }

    /// A `trajectory_connect` 0 arrived: the pending group starts (spline points merged).
    fn commit_group(&mut self) {
        let mut parts: Vec<Part> = Vec::new();
        for part in std::mem::take(&mut self.motion.pending) {
            match (parts.last_mut(), &part.goal) {
                (Some(last), Goal::Spline(points)) if matches!(last.goal, Goal::Spline(_)) => {
                    if let Goal::Spline(all) = &mut last.goal {
                        all.extend(points.iter().copied());
                    }
                    last.events += part.events;
                    last.end_rad = part.end_rad;
                }
                _ => parts.push(part),
            }
        }
        self.motion.queue.push_back(Run {
            parts,
            traj: None,
            part_ends_s: Vec::new(),
            done_parts: 0,
            t_s: 0.0,
            settle_ms: 0,
        });
    }

    /// Plan a group from `from`: each part from where the previous one ends, blended into one
    /// trajectory with the previous part's radius.
    fn plan_run(&self, from: &[f64], parts: &[Part]) -> Result<Trajectory, Refusal> {
        let mut whole: Option<Trajectory> = None;
        let mut start = from.to_vec();
        let mut radius = 0.0;
        for part in parts {
            let next = self.plan(&start, &part.goal, part.speed_percent)?;
            start = next.sample(next.duration_s());
            whole = Some(match whole {
                None => next,
                Some(prev) => planner::blend(&prev, &next, radius).map_err(|e| refusal_code(&e))?,
            });
            radius = part.blend_r;
        }
        whole.ok_or(codes::UNREACHABLE)
    }

    /// The running move failed (fault): `trajectory_state:false` to its client, queue dropped.
    pub(super) fn abort_motion(&mut self) {
        if let Some(part) = self.motion.queue.front().and_then(Run::current_part) {
            if let Some(client) = part.client {
                self.events.push(Event {
                    to: client,
                    text: arrival(false, 0, 0),
                });
            }
        }
        self.discard_motion();
    }

    /// Drop every move silently (stop commands; clients learn from `get_arm_current_trajectory`).
    pub(super) fn discard_motion(&mut self) {
        self.motion.queue.clear();
        self.motion.pending.clear();
        self.motion.jog = None;
        self.motion.stream = None;
        self.motion.scale = 1.0;
        self.motion.scale_target = 1.0;
        self.motion.at_rest = AtRest::Nothing;
        self.motion.stop_label = None;
    }

    pub(super) fn pause(&mut self) {
        self.motion.scale_target = 0.0;
        self.motion.ramp_per_s = PAUSE_RAMP_PER_S;
        self.motion.at_rest = AtRest::Pause;
    }

    pub(super) fn resume(&mut self) -> bool {
        if self.motion.at_rest != AtRest::Pause {
            return false;
        }
        self.motion.scale_target = 1.0;
        self.motion.ramp_per_s = PAUSE_RAMP_PER_S;
        self.motion.at_rest = AtRest::Nothing;
        true
    }

    pub(super) fn stop(&mut self, slow: bool) {
        self.motion.pending.clear();
        self.motion.jog = None;
        self.motion.stream = None;
        if self.motion.queue.is_empty() {
            // Nothing to brake: the arm is at rest (also ends a pause).
            self.discard_motion();
            return;
        }
        self.motion.scale_target = 0.0;
        self.motion.ramp_per_s = if slow {
            SLOW_STOP_RAMP_PER_S
        } else {
            STOP_RAMP_PER_S
        };
        self.motion.at_rest = AtRest::Discard;
        self.motion.stop_label = Some(if slow { "slow_stop" } else { "stop" });
    }

    /// Delete the running move (only while paused).
    pub(super) fn delete_current(&mut self) -> bool {
        if !self.motion.paused() {
            return false;
        }
        self.motion.queue.pop_front();
        true
    }

    /// Delete every move (only while paused).
    pub(super) fn delete_all(&mut self) -> bool {
        if !self.motion.paused() {
            return false;
        }
        self.motion.queue.clear();
        self.motion.pending.clear();
        true
    }

    pub(super) fn tick_motion(&mut self) {
        let m = &mut self.motion;
        let step = m.ramp_per_s * STEP_S;
        m.scale = if m.scale < m.scale_target {
            (m.scale + step).min(m.scale_target)
        } else {
            (m.scale - step).max(m.scale_target)
        };
        if m.scale <= 0.0 && m.at_rest == AtRest::Discard {
            self.discard_motion();
            return;
        }
        if !self.motion.queue.is_empty() {
            self.tick_segment();
        } else if let Some(jog) = self.motion.jog {
            self.tick_jog(jog);
        } else if self.motion.stream.is_some() {
            self.tick_stream();
        }
    }

    fn tick_segment(&mut self) {
        let from = self.setpoint_rad.clone();
        let Some(run) = self.motion.queue.front() else {
            return;
        };
        if run.traj.is_none() {
            match self.plan_run(&from, &run.parts) {
                Ok(traj) => {
                    if let Some(run) = self.motion.queue.front_mut() {
                        run.part_ends_s = traj.segment_end_times_s();
                        run.traj = Some(traj);
                    }
                }
                Err(code) => {
                    self.errors.planning = Some(code);
                    self.abort_motion();
                    return;
                }
            }
        }
        let scale = self.motion.scale;
        let Some(run) = self.motion.queue.front_mut() else {
            return;
        };
        let Some(traj) = &run.traj else {
            return;
        };
        let duration = traj.duration_s();
        run.t_s = (run.t_s + STEP_S * scale).min(duration);
        self.setpoint_rad = traj.sample(run.t_s);
        // Parts that ended inside a blended group: their events (connect 1) go out now.
        let last = run.parts.len().saturating_sub(1);
        let mut passed = Vec::new();
        while run.done_parts < last
            && run
                .part_ends_s
                .get(run.done_parts)
                .is_some_and(|end| run.t_s >= *end)
        {
            passed.push(run.parts[run.done_parts].clone());
            run.done_parts += 1;
        }
        let finished = run.t_s >= duration;
        if finished {
            run.settle_ms += 1;
        }
        let settle_ms = run.settle_ms;
        for part in &passed {
            self.part_events(part, false);
        }
        if !finished {
            return;
        }
        let settled = self
            .plant
            .positions_rad()
            .iter()
            .zip(&self.setpoint_rad)
            .all(|(q, s)| (q - s).abs() < ARRIVED_TOLERANCE_RAD);
        if settled || settle_ms >= SETTLE_TIMEOUT_MS {
            self.finish_run();
        }
    }

    /// The arrival events of one part; `last` = the group's final part (its final event
    /// carries `trajectory_connect` 0).
    fn part_events(&mut self, part: &Part, last: bool) {
        let Some(client) = part.client else {
            return;
        };
        for i in 0..part.events {
            let connect = u8::from(!last || i + 1 < part.events);
            self.events.push(Event {
                to: client,
                text: arrival(true, 0, connect),
            });
        }
    }

    fn finish_run(&mut self) {
        let Some(run) = self.motion.queue.pop_front() else {
            return;
        };
        let count = run.parts.len();
        for (i, part) in run.parts.iter().enumerate().skip(run.done_parts) {
            self.part_events(part, i + 1 == count);
        }
    }

    fn tick_jog(&mut self, jog: Jog) {
        let mut next = self.setpoint_rad.clone();
        match jog {
            Jog::Joint { joint, speed_rad_s } => next[joint] += speed_rad_s * STEP_S,
            Jog::Position { axis, speed_m_s } => {
                let mut pose = kinematics::forward(&self.model, &next);
                pose.position_m[axis] += speed_m_s * STEP_S;
                match self.solve(&pose, &next) {
                    Ok(q) => next = q,
                    Err(_) => next.clone_from(&self.setpoint_rad),
                }
            }
            Jog::Orientation { axis, speed_rad_s } => {
                let mut pose = kinematics::forward(&self.model, &next);
                pose.euler_rad[axis] += speed_rad_s * STEP_S;
                match self.solve(&pose, &next) {
                    Ok(q) => next = q,
                    Err(_) => next.clone_from(&self.setpoint_rad),
                }
            }
        }
        if self.beyond_limits(&next).is_some() || next == self.setpoint_rad {
            // A jog ends at a joint limit or where the arm cannot go further.
            self.motion.jog = None;
            return;
        }
        self.setpoint_rad = next;
    }

    fn tick_stream(&mut self) {
        let p = &self.params;
        let limits: Vec<JointLimits> = (0..self.setpoint_rad.len())
            .map(|j| JointLimits {
                min_rad: p.min_deg[j].to_radians(),
                max_rad: p.max_deg[j].to_radians(),
                speed_rad_s: p.max_speed_deg_s[j].to_radians(),
                acc_rad_s2: p.max_acc_deg_s2[j].to_radians(),
            })
            .collect();
        let Some(stream) = &mut self.motion.stream else {
            return;
        };
        let done = stream.advance(&mut self.setpoint_rad, &limits, STEP_S);
        if done && stream.idle_ms > STREAM_IDLE_MS {
            self.motion.stream = None;
        }
    }
}

/// The error a planning failure reports (docs/protocols/realman.md §12).
fn refusal_code(e: &PlanError) -> Refusal {
    match e {
        PlanError::OutOfLimits { .. }
        | PlanError::Unreachable {
            source: kinematics::IkError::OutOfLimits { .. },
            ..
        } => codes::BEYOND_JOINT_LIMIT,
        PlanError::DegenerateArc => codes::ARC_PLANNING,
        _ => codes::UNREACHABLE,
    }
}

/// `current_trajectory_state` event text.
pub(super) fn arrival(ok: bool, device: u8, connect: u8) -> String {
    Obj::state("current_trajectory_state")
        .bool("trajectory_state", ok)
        .int("device", i64::from(device))
        .int("trajectory_connect", i64::from(connect))
        .finish()
}
