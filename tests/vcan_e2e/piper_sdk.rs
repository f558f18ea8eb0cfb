//! vcan end-to-end: the vendor Python SDK (`piper_sdk`) against `armhil sim piper`.
//!
//! This check runs as the hook `scripts/e2e/piper_sdk.py` (started by `scripts/vcan-e2e.sh`
//! after this binary's tests): the script starts `$ARMHIL_BIN sim piper --iface
//! $ARMHIL_VCAN_IFACE` itself, drives it with `C_PiperInterface_V2(judge_flag=False)` and kills
//! it afterwards. It is deliberately not duplicated as a Rust test here, so the SDK check runs
//! exactly once per suite.
