"""Type stubs of the armhil extension module (the Arm API and the emulators)."""

from enum import IntEnum
from typing import Any, Callable, Dict, List, Optional, Tuple, Union, overload

class AbcErrorCode(IntEnum):
    """Result codes of the Arm API: SUCCESS (0) or a negative error code."""

    SUCCESS = 0
    UNKNOWN_ERROR = -1
    TIMEOUT = -2
    INVALID_HANDLE = -3
    INVALID_STATE = -4
    NOT_INITIALIZED = -5
    NOT_IMPLEMENTED = -6
    INVALID_ARGUMENT = -7
    PARAM_ERROR = -50
    PARAM_OUT_OF_RANGE = -51
    ARM_ERROR = -100
    ARM_CTRL_FALSE = -101
    ARM_DATA_SEND_FAILED = -102
    ARM_DATA_RECEIVE_FAILED = -103
    ARM_RETURN_DATA_ERR = -104
    ARM_CHECK_FAILED = -105
    ARM_TIMEOUT = -106
    ARM_OUT_OF_RANGE = -107

class Pose:
    """Flange pose: position in metres, Z-Y-X Euler angles in radians (R = Rz·Ry·Rx)."""

    position: List[float]
    euler: List[float]
    def __init__(
        self, position: Optional[List[float]] = None, euler: Optional[List[float]] = None
    ) -> None: ...

class JointState:
    joint_position: List[float]
    """Joint angles, degrees."""
    joint_speed: List[float]
    """Joint speeds, RPM."""
    joint_current: List[float]
    """Joint currents, mA."""
    joint_temperature: List[float]
    """Joint temperatures, °C."""
    joint_voltage: List[float]
    """Joint voltages, V."""
    joint_err_code: List[int]
    joint_en_flag: List[bool]
    def __init__(self) -> None: ...

class ArmForceSensor:
    force: List[float]
    """Raw sensor data, 0.001 N / 0.001 N·m."""
    zero_force: List[float]
    """External force, 0.001 N / 0.001 N·m."""
    coordinate: int
    """0 sensor frame, 1 work frame, 2 tool frame."""
    def __init__(self) -> None: ...

class GripperState:
    status: int
    """0 offline, 1 online, -1 online but disabled."""
    error: int
    mode: int
    """1 open idle, 2 closed idle, 3 stopped idle, 4 closing, 5 opening, 6 force stop."""
    current_force: int
    """Grams."""
    temperature: int
    """°C."""
    actpos: int
    """Aperture 0 (closed) – 1000 (open)."""
    def __init__(self) -> None: ...

class PeripheralReadWriteParams:
    port: int
    address: int
    device: int
    num: int
    def __init__(self, port: int = 0, address: int = 0, device: int = 0, num: int = 0) -> None: ...

class ArmRealtimeState:
    name: str
    timestamp: float
    """Wall-clock time of reception, seconds since the Unix epoch."""
    joint_status: JointState
    force_sensor: ArmForceSensor
    arm_current_status: str
    """idle, moving, paused, stopped, error or unknown."""
    gripper_state: Optional[GripperState]
    ee_pose: Pose

class ArmFactoryParam:
    """Parameters that create an arm; ArmFactoryParam(dict) raises RuntimeError on a
    missing or malformed key."""

    arm_type: str
    arm_name: str
    ip: str
    udp_ip: str
    port: int
    udp_port: int
    udp_cycle: int
    enable_gripper: bool
    can_interface: str
    socketcand: Optional[str]
    def __init__(self, arg0: Optional[Dict[str, str]] = None) -> None: ...

class ArmInterface:
    """One robot arm, whatever its vendor. Create it with ArmFactory."""

    @property
    def name(self) -> str: ...
    @property
    def last_error(self) -> str:
        """The message of the last failed call (empty when none failed)."""
    def capabilities(self) -> List[str]: ...
    def connect(self) -> AbcErrorCode: ...
    def disconnect(self) -> None: ...
    def move_joint_position(
        self, joints: List[float], v: int, r: int = 0, trajectory_connect: int = 0, block: int = 1
    ) -> AbcErrorCode: ...
    def move_cartesian_linear(
        self, pose: Pose, v: int, r: int = 0, trajectory_connect: int = 0, block: int = 1
    ) -> AbcErrorCode: ...
    def move_joint_pose(
        self, pose: Pose, v: int, r: int = 0, trajectory_connect: int = 0, block: int = 1
    ) -> AbcErrorCode: ...
    def move_joint_position_canfd(
        self, joints: List[float], follow: bool, trajectory_mode: int = 0, radio: int = 0
    ) -> AbcErrorCode: ...
    def move_cartesian_pose_canfd(
        self, pose: Pose, follow: bool, trajectory_mode: int = 0, radio: int = 0
    ) -> AbcErrorCode: ...
    def move_joint_follow(self, joints: List[float]) -> AbcErrorCode: ...
    def move_pose_follow(self, pose: Pose) -> AbcErrorCode: ...
    def realtime_arm_state_call_back(
        self, callback: Optional[Callable[[ArmRealtimeState], Any]]
    ) -> None: ...
    def set_arm_slow_stop(self) -> AbcErrorCode: ...
    def set_arm_stop(self) -> AbcErrorCode: ...
    def set_arm_pause(self) -> AbcErrorCode: ...
    def set_arm_continue(self) -> AbcErrorCode: ...
    def set_plus_mode(self, mode: int) -> AbcErrorCode: ...
    def set_gripper_release(self, speed: int, block: bool, timeout: int) -> AbcErrorCode: ...
    def set_gripper_pick(self, speed: int, force: int, block: bool, timeout: int) -> AbcErrorCode: ...
    def set_gripper_pick_on(
        self, speed: int, force: int, block: bool, timeout: int
    ) -> AbcErrorCode: ...
    def set_gripper_position(self, position: int, block: bool, timeout: int) -> AbcErrorCode: ...
    def get_gripper_state(self) -> Tuple[AbcErrorCode, GripperState]: ...
    def set_hand_posture(self, posture_num: int, block: bool, timeout: int) -> AbcErrorCode: ...
    def set_hand_angle(self, hand_angle: List[int]) -> AbcErrorCode: ...
    def set_hand_follow_angle(self, hand_angle: List[int], block: int) -> AbcErrorCode: ...
    def set_hand_follow_pos(self, hand_pos: List[int], block: int) -> AbcErrorCode: ...
    def set_hand_speed(self, speed: int) -> AbcErrorCode: ...
    def set_hand_force(self, hand_force: int) -> AbcErrorCode: ...
    def get_joint_degree(self) -> Tuple[AbcErrorCode, List[float]]: ...
    def forward_kinematics(self, joints: List[float]) -> Tuple[AbcErrorCode, Pose]: ...
    def inverse_kinematics(
        self, pose: Pose, ref_joints: List[float], mode: int = 0
    ) -> Tuple[AbcErrorCode, List[float]]: ...
    def set_modbus_mode(self, port: int, baudrate: int, timeout: int) -> AbcErrorCode: ...
    def close_modbus_mode(self, port: int) -> AbcErrorCode: ...
    def write_registers(
        self, params: PeripheralReadWriteParams, values: List[int]
    ) -> AbcErrorCode: ...
    def get_error_flag(self) -> Tuple[AbcErrorCode, Tuple[List[int], List[int]]]: ...

class ArmFactory:
    @overload
    @staticmethod
    def create_arm(
        vendor_type: str, name: str, params: Dict[str, str]
    ) -> Optional[ArmInterface]: ...
    @overload
    @staticmethod
    def create_arm(param: ArmFactoryParam) -> Optional[ArmInterface]: ...
    @staticmethod
    def create_arm_from_config(config_path: str) -> Optional[ArmInterface]: ...
    @staticmethod
    def last_error() -> str:
        """Why the last factory call returned None."""

class RealmanEmulator:
    @property
    def host(self) -> str: ...
    @property
    def port(self) -> int: ...
    @property
    def arm_type(self) -> str: ...
    @property
    def params(self) -> Dict[str, str]:
        """The params of ArmFactory.create_arm("realman", name, params)."""
    @property
    def running(self) -> bool: ...
    def faults(self) -> List[Dict[str, Any]]:
        """Every fault it takes: name, description, params (name, description, required,
        default, min, max, words), as scenario files name them."""
    @property
    def active_faults(self) -> List[str]:
        """Faults injected from Python and not cleared, as labels."""
    def config(self, arm_name: str = "arm") -> Dict[str, str]: ...
    def inject(self, name: str, **kwargs: Union[int, float, str]) -> None: ...
    def clear(self, name: str, **kwargs: Union[int, float, str]) -> None: ...
    def joints_deg(self) -> List[float]: ...
    def state(self) -> Dict[str, Any]: ...
    def connections(self) -> int: ...
    def stop(self) -> None: ...
    def __enter__(self) -> "RealmanEmulator": ...
    def __exit__(self, *args: Any) -> bool: ...

class PiperEmulator:
    @property
    def host(self) -> Optional[str]: ...
    @property
    def port(self) -> Optional[int]: ...
    @property
    def arm_type(self) -> str: ...
    @property
    def params(self) -> Dict[str, str]:
        """The params of ArmFactory.create_arm("piper", name, params)."""
    @property
    def running(self) -> bool: ...
    def faults(self) -> List[Dict[str, Any]]:
        """Every fault it takes: name, description, params (name, description, required,
        default, min, max, words), as scenario files name them."""
    @property
    def active_faults(self) -> List[str]:
        """Faults injected from Python and not cleared, as labels."""
    def config(self, arm_name: str = "arm") -> Dict[str, str]: ...
    def inject(self, name: str, **kwargs: Union[int, float, str]) -> None: ...
    def clear(self, name: str, **kwargs: Union[int, float, str]) -> None: ...
    def silence(self) -> None: ...
    def unsilence(self) -> None: ...
    def joints_deg(self) -> List[float]: ...
    def state(self) -> Dict[str, Any]: ...
    def stop(self) -> None: ...
    def __enter__(self) -> "PiperEmulator": ...
    def __exit__(self, *args: Any) -> bool: ...

class RobstrideEmulator:
    @property
    def host(self) -> Optional[str]: ...
    @property
    def port(self) -> Optional[int]: ...
    @property
    def params(self) -> Dict[str, str]: ...
    @property
    def running(self) -> bool: ...
    def faults(self) -> List[Dict[str, Any]]:
        """Every fault it takes: name, description, params (name, description, required,
        default, min, max, words), as scenario files name them."""
    @property
    def active_faults(self) -> List[str]:
        """Faults injected from Python and not cleared, as labels."""
    def inject(
        self, name: str, can_id: Optional[int] = None, **kwargs: Union[int, float, str]
    ) -> None:
        """Injects fault `name` of `faults()`, its arguments by keyword: `motor=` (CAN ID) and
        the fault's own values, e.g. `inject("encoder_glitch", motor=3, counts=100)`.
        `ValueError` when the fault builder refuses them. `can_id` is the old spelling of
        `motor=` (deprecated: DeprecationWarning)."""
    def clear(
        self, name: str, can_id: Optional[int] = None, **kwargs: Union[int, float, str]
    ) -> None:
        """Removes fault `name`'s cause on `motor=` (a fault's values may be left out)."""
    def state(self) -> List[Dict[str, Any]]: ...
    def stop(self) -> None: ...
    def __enter__(self) -> "RobstrideEmulator": ...
    def __exit__(self, *args: Any) -> bool: ...

class DamiaoEmulator:
    @property
    def host(self) -> Optional[str]: ...
    @property
    def port(self) -> Optional[int]: ...
    @property
    def params(self) -> Dict[str, str]: ...
    @property
    def running(self) -> bool: ...
    def faults(self) -> List[Dict[str, Any]]:
        """Every fault it takes: name, description, params (name, description, required,
        default, min, max, words), as scenario files name them."""
    @property
    def active_faults(self) -> List[str]:
        """Faults injected from Python and not cleared, as labels."""
    def inject(self, name: str, **kwargs: Union[int, float, str]) -> None:
        """Injects fault `name` of `faults()`, its arguments by keyword: `motor=` (ESC_ID) and
        the fault's own values, e.g. `inject("over_voltage", motor=1, voltage_v=40)`.
        `ValueError` when the fault builder refuses them."""
    def clear(self, name: str, **kwargs: Union[int, float, str]) -> None:
        """Removes fault `name`'s cause on `motor=` (the error stays latched until the host
        clears it)."""
    def state(self) -> List[Dict[str, Any]]:
        """Per motor: can_id, mst_id, model, enabled, mode, ctrl_mode, state, angle_rad,
        speed_rad_s, torque_nm, temperature_c, mos_temperature_c, bus_voltage_v, faults."""
    def stop(self) -> None: ...
    def __enter__(self) -> "DamiaoEmulator": ...
    def __exit__(self, *args: Any) -> bool: ...

class RobotEmulator:
    @property
    def name(self) -> str: ...
    @property
    def buses(self) -> List[str]: ...
    @property
    def actuators(self) -> Dict[str, Tuple[str, int]]: ...
    @property
    def host(self) -> Optional[str]: ...
    @property
    def port(self) -> Optional[int]: ...
    @property
    def running(self) -> bool: ...
    def faults(self) -> List[Dict[str, Any]]:
        """Every fault it takes: name, description, params (name, description, required,
        default, min, max, words), as scenario files name them."""
    @property
    def active_faults(self) -> List[str]:
        """Faults injected from Python and not cleared, as labels."""
    def inject(
        self, name: str, joint: Optional[str] = None, **kwargs: Union[int, float, str]
    ) -> None:
        """Injects fault `name` of `faults()`, its arguments by keyword: RobStride's faults on
        `joint=` with their values (`inject("encoder_glitch", joint="left_knee", counts=100)`),
        `external_torque` (`joint=`, `torque_nm=`), `bus_lost` (`bus=`), `gantry_release`.
        `ValueError` when the fault builder refuses them."""
    def clear(
        self, name: str, joint: Optional[str] = None, **kwargs: Union[int, float, str]
    ) -> None:
        """Removes fault `name`'s cause (`joint=` or `bus=`; a fault's values may be left out)."""
    def set_temperature(self, joint: str, celsius: float) -> None: ...
    def set_external_torque(self, joint: str, torque_nm: float) -> None: ...
    def bus_lost(self, bus: str, lost: bool = True) -> None: ...
    def release_gantry(self) -> None:
        """The gantry lets go of the base: the robot stands on its actuators or falls."""
    def state(self) -> Dict[str, Any]: ...
    def stop(self) -> None: ...
    def __enter__(self) -> "RobotEmulator": ...
    def __exit__(self, *args: Any) -> bool: ...

def sim_realman(
    port: int = 0,
    host: str = "127.0.0.1",
    model: str = "RM65-B",
    firmware: str = "V1.7.0",
    initial_joints_deg: Optional[List[float]] = None,
    gripper: bool = True,
) -> RealmanEmulator: ...
def sim_piper(
    iface: Optional[str] = None,
    socketcand: str = "127.0.0.1:0",
    firmware: str = "S-V1.8-2",
    initial_joints_deg: Optional[List[float]] = None,
) -> PiperEmulator: ...
def sim_robstride(
    motors: Optional[List[str]] = None,
    iface: Optional[str] = None,
    socketcand: str = "127.0.0.1:0",
) -> RobstrideEmulator: ...
def sim_damiao(
    motors: Optional[List[str]] = None,
    iface: Optional[str] = None,
    socketcand: str = "127.0.0.1:0",
) -> DamiaoEmulator: ...
def sim_robot(
    file: str,
    socketcand: str = "127.0.0.1:0",
    interfaces: bool = False,
    state_file: Optional[str] = None,
    gantry: Optional[str] = None,
) -> RobotEmulator: ...
