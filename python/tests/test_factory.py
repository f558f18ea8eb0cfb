"""ArmFactory, ArmFactoryParam and AbcErrorCode: construction and its error paths."""

import json

import pytest

from armhil import AbcErrorCode, ArmFactory, ArmFactoryParam

SEED_DICT = {
    "arm_type": "realman",
    "arm_name": "left_arm",
    "ip": "192.168.1.10",
    "port": "5000",
    "udp_ip": "192.168.1.100",
    "udp_port": "6000",
    "udp_cycle": "20",
    "enable_gripper": "false",
}


def test_error_codes_are_an_int_enum_with_the_api_values():
    from enum import IntEnum

    assert issubclass(AbcErrorCode, IntEnum)
    expected = {
        "SUCCESS": 0, "UNKNOWN_ERROR": -1, "TIMEOUT": -2, "INVALID_HANDLE": -3,
        "INVALID_STATE": -4, "NOT_INITIALIZED": -5, "NOT_IMPLEMENTED": -6,
        "INVALID_ARGUMENT": -7, "PARAM_ERROR": -50, "PARAM_OUT_OF_RANGE": -51,
        "ARM_ERROR": -100, "ARM_CTRL_FALSE": -101, "ARM_DATA_SEND_FAILED": -102,
        "ARM_DATA_RECEIVE_FAILED": -103, "ARM_RETURN_DATA_ERR": -104,
        "ARM_CHECK_FAILED": -105, "ARM_TIMEOUT": -106, "ARM_OUT_OF_RANGE": -107,
    }
    assert {m.name: m.value for m in AbcErrorCode} == expected


def test_param_from_the_seed_dictionary():
    p = ArmFactoryParam(SEED_DICT)
    assert (p.arm_type, p.arm_name, p.ip, p.udp_ip) == ("realman", "left_arm", "192.168.1.10", "192.168.1.100")
    assert (p.port, p.udp_port, p.udp_cycle) == (5000, 6000, 20)
    assert isinstance(p.port, int)
    p.port = 8080
    p.arm_name = "right_arm"
    assert (p.port, p.arm_name) == (8080, "right_arm")
    arm = ArmFactory.create_arm(p)
    assert arm is not None and arm.name == "right_arm"


@pytest.mark.parametrize("key", ["arm_type", "arm_name", "ip", "port", "udp_ip", "udp_port", "udp_cycle"])
def test_param_missing_key_is_a_runtime_error(key):
    d = dict(SEED_DICT)
    del d[key]
    with pytest.raises(RuntimeError, match=key):
        ArmFactoryParam(d)


@pytest.mark.parametrize("key,value", [("port", "80x0"), ("ip", "1.2.3"), ("udp_cycle", "0"),
                                       ("enable_gripper", "maybe"), ("arm_type", "kuka")])
def test_param_malformed_value_is_a_runtime_error(key, value):
    d = dict(SEED_DICT, **{key: value})
    with pytest.raises(RuntimeError):
        ArmFactoryParam(d)


def test_param_setters_check_values():
    p = ArmFactoryParam()
    with pytest.raises(RuntimeError):
        p.port = 70000
    with pytest.raises(RuntimeError):
        p.arm_type = "kuka"
    p.arm_type = "piper"
    p.socketcand = "127.0.0.1:29536"
    assert ArmFactory.create_arm(p).capabilities()[0] == "connect"


def test_create_arm_with_bad_params_is_none():
    assert ArmFactory.create_arm("realman", "a", {"ip": "127.0.0.1"}) is None
    assert "udp_ip" in ArmFactory.last_error() or "port" in ArmFactory.last_error()
    assert ArmFactory.create_arm("kuka", "a", {}) is None
    assert "kuka" in ArmFactory.last_error()
    arm = ArmFactory.create_arm("piper", "p", {"socketcand": "127.0.0.1:1"})
    assert arm is not None


def test_config_file_errors_are_none(tmp_path):
    assert ArmFactory.create_arm_from_config(str(tmp_path / "missing.json")) is None
    bad = tmp_path / "bad.json"
    bad.write_text("{ not json")
    assert ArmFactory.create_arm_from_config(str(bad)) is None
    assert "bad.json" in ArmFactory.last_error()
    good = tmp_path / "arm.json"
    good.write_text(json.dumps(SEED_DICT))
    arm = ArmFactory.create_arm_from_config(str(good))
    assert arm is not None and arm.name == "left_arm"


def test_connecting_to_nothing_fails_with_a_code(tmp_path):
    arm = ArmFactory.create_arm("piper", "p", {"socketcand": "127.0.0.1:1"})
    assert arm.connect() == AbcErrorCode.ARM_DATA_SEND_FAILED
    arm = ArmFactory.create_arm("realman", "r", dict(SEED_DICT, ip="127.0.0.1", port="1"))
    assert arm.connect() == AbcErrorCode.ARM_DATA_SEND_FAILED
