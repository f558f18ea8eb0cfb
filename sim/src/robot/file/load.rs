//! Reading a robot file into the emulator's [`RobotConfig`] (layer 2): every problem names
//! file, line and column; doubtful but runnable choices come back as warnings.

use std::path::{Path, PathBuf};

use super::error::{FileError, Position as Pos};
use super::raw::{RawRobot, RawSelfCollision, S};
use crate::actuator::{self, ConfigureError};
use crate::bounded_read::read_text_file;
use crate::description::{Description, DescriptionError, MissingMeshes, PackagePaths};
use crate::physics::{read_urdf, ArmModel, JointKind, Solver, WorldConfig};
use crate::robot::{Base, BusConfig, Gantry, JointActuator, RobotConfig};
use crate::robstride::DEFAULT_HOST_ID;
use crate::yaml_words::suggestion;

fn pos<T>(value: &S<T>) -> Pos {
    Pos::of(value)
}

/// The CAN FD data-phase bit rates a robot file's bus may give (bit/s): what FD controllers
/// and transceivers commonly run (the OpenArm: 5 Mbit/s).
const FD_DATA_BITRATES_BPS: [u32; 5] = [1_000_000, 2_000_000, 4_000_000, 5_000_000, 8_000_000];

/// Largest robot file read (bytes). The humanoid's is under 4 KB.
const MAX_ROBOT_FILE_BYTES: u64 = 1024 * 1024;

/// A robot file that loaded.
#[derive(Debug, Clone)]
pub struct LoadedRobot {
    /// What the emulator runs.
    pub config: RobotConfig,
    /// The robot file.
    pub file: PathBuf,
    /// The URDF file it names.
    pub urdf_path: PathBuf,
    /// Whether the file says `gantry:` (else a front end may choose its own default).
    pub gantry_given: bool,
    /// Choices that run but are probably wrong (an actuator weaker than its joint's URDF
    /// effort), each at its place in the file.
    pub warnings: Vec<FileError>,
}

impl LoadedRobot {
    /// The gantry a front end serving the robot to a user's stack (`armhil sim robot`,
    /// Python) runs it with: `requested` (its own option), else the file's `gantry:`, else,
    /// for a floating base, `until_enabled` — a user bringing a robot up expects it on its
    /// stand until its actuators hold it. Scenarios keep the file's (`off` when unsaid).
    pub fn serving_gantry(&self, requested: Option<Gantry>) -> Gantry {
        match (requested, self.gantry_given, self.config.base) {
            (Some(gantry), ..) => gantry,
            (None, true, _) | (None, false, Base::Fixed) => self.config.gantry,
            (None, false, Base::Floating { .. }) => Gantry::UntilEnabled,
        }
    }
}

/// Why a robot file could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum RobotFileError {
    /// The file could not be read (missing, not a regular file, too large).
    #[error("{}: {message}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// The file was read but is not a valid robot file.
    #[error("{0}")]
    Invalid(#[from] Box<FileError>),
}

/// Loads and checks the robot file `path` and the URDF it names.
pub fn load_robot_file(path: &Path) -> Result<LoadedRobot, RobotFileError> {
    let text = read_text_file(path, MAX_ROBOT_FILE_BYTES, "robot file").map_err(|message| {
        RobotFileError::Read {
            path: path.to_owned(),
            message,
        }
    })?;
    let raw: RawRobot = serde_saphyr::from_str(&text)
        .map_err(|e| Box::new(FileError::from_yaml(path, &text, &e)))?;
    let checker = Checker {
        file: path,
        text: &text,
    };
    checker.check(raw).map_err(RobotFileError::Invalid)
}

struct Checker<'a> {
    file: &'a Path,
    text: &'a str,
}

type Res<T> = Result<T, Box<FileError>>;

impl Checker<'_> {
    fn err(&self, at: Pos, message: impl Into<String>) -> Box<FileError> {
        Box::new(FileError::new(self.file, self.text, at, message))
    }

    fn check(&self, raw: RawRobot) -> Res<LoadedRobot> {
        let dir = self.file.parent().unwrap_or(Path::new("."));
        let urdf_path = dir.join(&raw.urdf.value);
        let urdf_name = &raw.urdf.value;
        let urdf = read_urdf(&urdf_path).map_err(|e| {
            self.err(
                pos(&raw.urdf),
                format!("the URDF `{urdf_name}` does not load: {e}"),
            )
        })?;
        // A problem inside the URDF names the URDF's own line.
        let in_urdf = |e: DescriptionError| {
            let line = e.line.map(|l| format!(" line {l}")).unwrap_or_default();
            self.err(
                pos(&raw.urdf),
                format!("the URDF `{urdf_name}`{line}: {}", e.message),
            )
        };
        let packages = self.packages(&raw, dir)?;
        let paths = PackagePaths::for_urdf(&urdf_path, packages);
        let description = Description::parse(urdf, paths.clone()).map_err(in_urdf)?;
        let model = ArmModel::from_robot(description.robot()).map_err(|e| {
            self.err(
                pos(&raw.urdf),
                format!("the URDF `{urdf_name}` does not load: {e}"),
            )
        })?;
        let missing_meshes = self.missing_meshes(&raw)?;
        let convex_decomposition = self.decomposed_links(&raw, &model)?;
        let collision = description
            .collision_geometry_decomposed(missing_meshes, &convex_decomposition)
            .map_err(in_urdf)?;
        let physics = self.physics(&raw)?;
        // What the physics refuses (a joint that moves nothing with mass), said now.
        physics
            .load(&description, &collision, WorldConfig::default())
            .map_err(|e| {
                self.err(
                    pos(&raw.urdf),
                    format!("the URDF `{urdf_name}` does not load: {e}"),
                )
            })?;
        let mut warnings = Vec::new();
        for skipped in &collision.skipped {
            warnings.push(*self.err(pos(&raw.urdf), format!("the URDF `{urdf_name}`: {skipped}")));
        }
        if let Some(summary) = description.unused_summary() {
            warnings.push(*self.err(pos(&raw.urdf), format!("the URDF `{urdf_name}`: {summary}")));
        }
        let self_collision = self.self_collision(&raw, &model)?;
        let urdf = description.text().to_owned();
        let base = self.base(&raw)?;
        let gantry = self.gantry(&raw, base)?;
        let buses = self.buses(&raw)?;
        let mut actuators: Vec<JointActuator> = Vec::new();
        let movable: Vec<&str> = model.joints().iter().map(|j| j.name.as_str()).collect();
        for a in &raw.actuators.value {
            let a = &a.value;
            let joint = self.joint(&a.joint, &movable)?;
            let info = &model.joints()[joint];
            if info.kind != JointKind::Revolute {
                return Err(self.err(
                    pos(&a.joint),
                    format!(
                        "joint `{}` is prismatic; the actuators a robot file names turn",
                        info.name
                    ),
                ));
            }
            if let Some(mimic) = &info.mimic {
                return Err(self.err(
                    pos(&a.joint),
                    format!(
                        "joint `{}` follows `{}` through the URDF's <mimic>: it moves with its leader; put the actuator on `{}`",
                        info.name, mimic.leader, mimic.leader
                    ),
                ));
            }
            if let Some(other) = actuators.iter().find(|o| o.joint == info.name) {
                return Err(self.err(
                    pos(&a.joint),
                    format!(
                        "joint `{}` already has an actuator (id {})",
                        other.joint,
                        other.actuator.can_id()
                    ),
                ));
            }
            // The model names the kind (RS03: RobStride); the id is checked by that kind.
            let can_id = u32::try_from(a.id.value).unwrap_or(u32::MAX);
            let config = match actuator::configure(&a.model.value, can_id) {
                Ok(config) => config,
                Err(e @ ConfigureError::UnknownModel { .. }) => {
                    return Err(self.err(pos(&a.model), e.to_string()))
                }
                Err(ConfigureError::IdOutOfRange {
                    kind, low, high, ..
                }) => {
                    return Err(self.err(
                        pos(&a.id),
                        format!(
                            "`id` must be {low}..={high} for a {kind} actuator, got {}",
                            a.id.value
                        ),
                    ));
                }
            };
            let names: Vec<&str> = buses.iter().map(|b| b.name.as_str()).collect();
            let bus = names
                .iter()
                .position(|n| *n == a.bus.value)
                .ok_or_else(|| {
                    self.err(
                        pos(&a.bus),
                        format!(
                            "no bus `{}` in `buses` (they are: {}){}",
                            a.bus.value,
                            names.join(", "),
                            suggestion(&a.bus.value, &names)
                        ),
                    )
                })?;
            if let Some(other) = actuators
                .iter()
                .find(|o| o.bus == bus && o.actuator.can_id() == can_id)
            {
                return Err(self.err(
                    pos(&a.id),
                    format!(
                        "id {can_id} is already joint `{}`'s on bus `{}`: two actuators on one bus need two ids",
                        other.joint, names[bus]
                    ),
                ));
            }
            let direction = match a.direction.as_ref().map(|d| d.value) {
                None | Some(1) => 1.0,
                Some(-1) => -1.0,
                Some(other) => {
                    let at = a.direction.as_ref().map(pos).unwrap_or_default();
                    return Err(self.err(at, format!("`direction` must be 1 or -1, got {other}")));
                }
            };
            let zero_offset_rad = match &a.zero_offset_rad {
                None => 0.0,
                Some(z) if z.value.is_finite() && z.value.abs() <= 4.0 * std::f64::consts::PI => {
                    z.value
                }
                Some(z) => {
                    return Err(self.err(
                        pos(z),
                        format!("`zero_offset_rad` must be within ±4π, got {}", z.value),
                    ))
                }
            };
            let kind = config.kind();
            if buses[bus].data_bitrate_bps.is_some() && !kind.fd {
                return Err(self.err(
                    pos(&a.bus),
                    format!(
                        "bus `{}` runs CAN FD (`data_bitrate`); a {} actuator is a classic CAN controller and would destroy every FD frame on it",
                        names[bus], kind.name
                    ),
                ));
            }
            let bitrate = buses[bus].bitrate_bps;
            if !kind.bitrates_bps.contains(&bitrate) {
                let rates: Vec<String> = kind.bitrates_bps.iter().map(u32::to_string).collect();
                return Err(self.err(
                    pos(&a.bus),
                    format!(
                        "bus `{}` runs at {bitrate} bit/s; a {} actuator runs at {}",
                        names[bus],
                        kind.name,
                        rates.join(", ")
                    ),
                ));
            }
            let model = config.model();
            let peak = model.peak_torque_nm;
            if info.effort_limit.is_finite() && peak + 1e-9 < info.effort_limit {
                warnings.push(*self.err(
                    pos(&a.model),
                    format!(
                        "{} peaks at {peak} N·m, below joint `{}`'s URDF effort of {} N·m",
                        model.name, info.name, info.effort_limit
                    ),
                ));
            }
            actuators.push(JointActuator {
                joint: info.name.clone(),
                bus,
                actuator: config,
                direction,
                zero_offset_rad,
            });
        }
        for (k, b) in raw.buses.value.iter().enumerate() {
            if !actuators.iter().any(|a| a.bus == k) {
                return Err(self.err(
                    pos(&b.value.name),
                    format!("bus `{}` has no actuator on it", b.value.name.value),
                ));
            }
        }
        let start_positions_rad = self.start_positions(&raw, &model, &movable, &mut warnings)?;
        Ok(LoadedRobot {
            config: RobotConfig {
                name: raw.robot.value.clone(),
                urdf,
                urdf_paths: paths,
                missing_meshes,
                self_collision,
                convex_decomposition,
                collision: Some(std::sync::Arc::new(collision)),
                base,
                gantry,
                physics,
                buses,
                actuators,
                start_positions_rad,
                state_file: None,
                host_id: DEFAULT_HOST_ID,
            },
            file: self.file.to_owned(),
            gantry_given: raw.gantry.is_some(),
            urdf_path,
            warnings,
        })
    }

    /// Every movable joint's start: as given, or 0; one outside its limits starts at the
    /// nearest limit with a warning naming it (the same rule for given and default starts,
    /// so a URDF whose joint cannot be at 0 runs without a `start_rad` entry for it).
    fn start_positions(
        &self,
        raw: &RawRobot,
        model: &ArmModel,
        movable: &[&str],
        warnings: &mut Vec<FileError>,
    ) -> Res<Vec<(String, f64)>> {
        let mut given: Vec<(usize, f64, Pos)> = Vec::new();
        for s in raw.start_rad.iter().flat_map(|s| &s.value) {
            let s = &s.value;
            let joint = self.joint(&s.joint, movable)?;
            if given.iter().any(|(j, ..)| *j == joint) {
                return Err(self.err(
                    pos(&s.joint),
                    format!("joint `{}` is given a start twice", s.joint.value),
                ));
            }
            if !s.rad.value.is_finite() {
                return Err(self.err(
                    pos(&s.rad),
                    format!("a start must be a finite number, got {}", s.rad.value),
                ));
            }
            given.push((joint, s.rad.value, pos(&s.rad)));
        }
        let mut starts = Vec::new();
        for (joint, info) in model.joints().iter().enumerate() {
            if info.mimic.is_some() {
                continue;
            }
            let (value, at, how) = match given.iter().find(|(j, ..)| *j == joint) {
                Some((_, value, at)) => (*value, *at, "given"),
                None => (0.0, pos(&raw.urdf), "default"),
            };
            let start = value.clamp(info.lower, info.upper);
            if start != value {
                warnings.push(*self.err(
                    at,
                    format!(
                        "joint `{}` starts at {start} rad, its nearest limit: the {how} start {value} rad is outside its limits [{}, {}]",
                        info.name, info.lower, info.upper
                    ),
                ));
            }
            if how == "given" || start != value {
                starts.push((info.name.clone(), start));
            }
        }
        Ok(starts)
    }

    /// The robot file's `packages` map, folders relative to the robot file.
    fn packages(&self, raw: &RawRobot, dir: &Path) -> Res<Vec<(String, PathBuf)>> {
        let Some(map) = &raw.packages else {
            return Ok(Vec::new());
        };
        let mut packages = Vec::new();
        for (name, folder) in &map.value {
            let path = dir.join(&folder.value);
            if !path.is_dir() {
                return Err(self.err(
                    pos(folder),
                    format!("package `{name}`: `{}` is not a folder", path.display()),
                ));
            }
            packages.push((name.clone(), path));
        }
        Ok(packages)
    }

    /// The floating base's stand (none for a fixed base).
    fn gantry(&self, raw: &RawRobot, base: Base) -> Res<Gantry> {
        let Some(word) = &raw.gantry else {
            return Ok(Gantry::Off);
        };
        if base == Base::Fixed {
            return Err(self.err(
                pos(word),
                "`gantry` holds a floating base; a fixed base is bolted down already",
            ));
        }
        Gantry::parse(&word.value).map_err(|e| self.err(pos(word), format!("`gantry` {e}")))
    }

    /// `self_collision:`: off, on, or on without the pairs it lists (links of the URDF).
    fn self_collision(
        &self,
        raw: &RawRobot,
        model: &ArmModel,
    ) -> Res<Option<Vec<(String, String)>>> {
        // The names' own places are lost inside the untagged choice: the key's is used.
        let at = raw.self_collision.as_ref().map(pos).unwrap_or_default();
        match raw.self_collision.as_ref().map(|s| &s.value) {
            None | Some(RawSelfCollision::Switch(false)) => Ok(None),
            Some(RawSelfCollision::Switch(true)) => Ok(Some(Vec::new())),
            Some(RawSelfCollision::Except(pairs)) => {
                let mut out = Vec::with_capacity(pairs.len());
                for [a, b] in pairs {
                    for name in [a, b] {
                        self.link(model, &name.value, at, "self_collision")?;
                    }
                    out.push((a.value.clone(), b.value.clone()));
                }
                Ok(Some(out))
            }
        }
    }

    /// `convex_decomposition:`: links of the URDF, each named once.
    fn decomposed_links(&self, raw: &RawRobot, model: &ArmModel) -> Res<Vec<String>> {
        let mut out: Vec<String> = Vec::new();
        for name in raw.convex_decomposition.iter().flat_map(|l| &l.value) {
            self.link(model, &name.value, pos(name), "convex_decomposition")?;
            if !out.contains(&name.value) {
                out.push(name.value.clone());
            }
        }
        Ok(out)
    }

    /// `name` must be a link of the URDF; else an error at `at` for key `key`, with the
    /// nearest link's name.
    fn link(&self, model: &ArmModel, name: &str, at: Pos, key: &str) -> Res<()> {
        if model.link_index(name).is_some() {
            return Ok(());
        }
        let links: Vec<&str> = model.link_names().iter().map(String::as_str).collect();
        Err(self.err(
            at,
            format!(
                "`{key}`: the URDF has no link `{name}`{}",
                suggestion(name, &links)
            ),
        ))
    }

    fn missing_meshes(&self, raw: &RawRobot) -> Res<MissingMeshes> {
        match raw.missing_meshes.as_ref().map(|m| (m.value.as_str(), m)) {
            None | Some(("refuse", _)) => Ok(MissingMeshes::Refuse),
            Some(("skip", _)) => Ok(MissingMeshes::Skip),
            Some((other, at)) => Err(self.err(
                pos(at),
                format!("`missing_meshes` must be `refuse` or `skip`, got `{other}`"),
            )),
        }
    }

    /// `physics:`: the solver, and what only the articulated solver does (a gantry holding
    /// a floating base, self-collision) refused with rapier's.
    fn physics(&self, raw: &RawRobot) -> Res<Solver> {
        let Some(word) = &raw.physics else {
            return Ok(Solver::default());
        };
        let words: Vec<&str> = Solver::ALL.iter().map(|s| s.word()).collect();
        let solver = Solver::parse(&word.value).ok_or_else(|| {
            self.err(
                pos(word),
                format!(
                    "`physics` must be {}, got `{}`{}",
                    words
                        .iter()
                        .map(|w| format!("`{w}`"))
                        .collect::<Vec<_>>()
                        .join(" or "),
                    word.value,
                    suggestion(&word.value, &words)
                ),
            )
        })?;
        if solver == Solver::Rapier {
            let gantry_holds = raw
                .gantry
                .as_ref()
                .is_some_and(|g| Gantry::parse(&g.value).is_ok_and(|g| g != Gantry::Off));
            if gantry_holds {
                return Err(self.err(
                    pos(word),
                    "`physics: rapier` cannot hold a floating base on a gantry (rapier's root is fixed or free for good): use `physics: articulated` or `gantry: off`",
                ));
            }
            if raw
                .self_collision
                .as_ref()
                .is_some_and(|c| !matches!(c.value, RawSelfCollision::Switch(false)))
            {
                return Err(self.err(
                    pos(word),
                    "`physics: rapier` has no self-collision (the articulated solver's): use `physics: articulated` or leave `self_collision` out",
                ));
            }
        }
        Ok(solver)
    }

    fn base(&self, raw: &RawRobot) -> Res<Base> {
        let floating = match raw.base.as_ref().map(|b| b.value.as_str()) {
            None | Some("fixed") => false,
            Some("floating") => true,
            Some(other) => {
                let at = raw.base.as_ref().map(pos).unwrap_or_default();
                return Err(self.err(
                    at,
                    format!("`base` must be `fixed` or `floating`, got `{other}`"),
                ));
            }
        };
        match (floating, &raw.start_height_m) {
            (false, None) => Ok(Base::Fixed),
            (false, Some(h)) => Err(self.err(
                pos(h),
                "`start_height_m` is for a floating base; a fixed base stays where the URDF puts it",
            )),
            (true, None) => Err(self.err(
                raw.base.as_ref().map(pos).unwrap_or_default(),
                "a floating base needs `start_height_m`: the root link's height above the ground at start",
            )),
            (true, Some(h)) if h.value.is_finite() && (0.0..=10.0).contains(&h.value) => {
                Ok(Base::Floating {
                    start_height_m: h.value,
                })
            }
            (true, Some(h)) => Err(self.err(
                pos(h),
                format!("`start_height_m` must be 0..=10 m, got {}", h.value),
            )),
        }
    }

    fn buses(&self, raw: &RawRobot) -> Res<Vec<BusConfig>> {
        if raw.buses.value.is_empty() {
            return Err(self.err(pos(&raw.buses), "a robot needs at least one bus"));
        }
        let mut buses: Vec<BusConfig> = Vec::new();
        for b in &raw.buses.value {
            let b = &b.value;
            let name = &b.name.value;
            let valid = !name.is_empty()
                && name.len() <= 15
                && name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
            if !valid {
                return Err(self.err(
                    pos(&b.name),
                    format!("bus name `{name}` must be 1 to 15 letters, digits, `_` or `-` (it names a network interface)"),
                ));
            }
            if buses.iter().any(|o| &o.name == name) {
                return Err(self.err(pos(&b.name), format!("bus `{name}` is listed twice")));
            }
            // Any rate an actuator kind runs at; each actuator is checked against its bus's.
            let mut bitrates: Vec<u32> = actuator::KINDS
                .iter()
                .flat_map(|k| k.bitrates_bps.iter().copied())
                .collect();
            bitrates.sort_unstable_by(|a, b| b.cmp(a));
            bitrates.dedup();
            let bitrate_bps = match &b.bitrate {
                None => 1_000_000,
                Some(r) => match u32::try_from(r.value).ok().filter(|v| bitrates.contains(v)) {
                    Some(v) => v,
                    None => {
                        let list: Vec<String> = bitrates.iter().map(u32::to_string).collect();
                        return Err(self.err(
                            pos(r),
                            format!(
                                "`bitrate` {} is not one an actuator runs at ({})",
                                r.value,
                                list.join(", ")
                            ),
                        ));
                    }
                },
            };
            let data_bitrate_bps = match &b.data_bitrate {
                None => None,
                Some(r) => match u32::try_from(r.value)
                    .ok()
                    .filter(|v| FD_DATA_BITRATES_BPS.contains(v) && *v >= bitrate_bps)
                {
                    Some(v) => Some(v),
                    None => {
                        let list: Vec<String> =
                            FD_DATA_BITRATES_BPS.iter().map(u32::to_string).collect();
                        return Err(self.err(
                            pos(r),
                            format!(
                                "`data_bitrate` {} must be one of {} and at least the bus's `bitrate` ({bitrate_bps})",
                                r.value,
                                list.join(", ")
                            ),
                        ));
                    }
                },
            };
            buses.push(BusConfig {
                name: name.clone(),
                bitrate_bps,
                data_bitrate_bps,
            });
        }
        Ok(buses)
    }

    fn joint(&self, name: &S<String>, movable: &[&str]) -> Res<usize> {
        movable
            .iter()
            .position(|j| *j == name.value)
            .ok_or_else(|| {
                self.err(
                    pos(name),
                    format!(
                        "the URDF has no movable joint `{}`{}",
                        name.value,
                        suggestion(&name.value, movable)
                    ),
                )
            })
    }
}
