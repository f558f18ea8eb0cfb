//! The CiA-402 power drive state machine, pure: controlword commands in, next state out, and
//! the statusword bits of each state. What a state does to the motor lives in the parent.

/// A state of the drive state machine. "Not ready to switch on" and "fault reaction active"
/// are transient on this drive (self-test and the torque cut take no time), so they are never
/// observed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum DriveState {
    /// Torque off; the state after power-on and after a fault reset.
    SwitchOnDisabled,
    /// Torque off, ready for "switch on".
    ReadyToSwitchOn,
    /// Torque off, switched on.
    SwitchedOn,
    /// The motor runs in the selected mode of operation.
    OperationEnabled,
    /// Braking to standstill, then holding zero speed.
    QuickStopActive,
    /// A fault is latched; torque off until a fault reset.
    Fault,
}

/// A command decoded from the controlword (bits 0–3 and 7).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Command {
    /// xxxx x110.
    Shutdown,
    /// xxxx 0111 (also "disable operation" from Operation enabled).
    SwitchOn,
    /// xxxx 1111: switch on and enable operation.
    EnableOperation,
    /// xxxx xx0x.
    DisableVoltage,
    /// xxxx x01x.
    QuickStop,
    /// Bit 7 rising.
    FaultReset,
}

/// Fault reset bit of the controlword.
const FAULT_RESET: u16 = 1 << 7;

/// The command a controlword gives, `previous` being the last one written (bit 7 acts on its
/// rising edge).
pub(super) fn decode(controlword: u16, previous: u16) -> Command {
    if controlword & FAULT_RESET != 0 && previous & FAULT_RESET == 0 {
        return Command::FaultReset;
    }
    let low = controlword & 0x0F;
    if low & 0b0010 == 0 {
        Command::DisableVoltage
    } else if low & 0b0100 == 0 {
        Command::QuickStop
    } else if low & 0b0001 == 0 {
        Command::Shutdown
    } else if low & 0b1000 == 0 {
        Command::SwitchOn
    } else {
        Command::EnableOperation
    }
}

/// The state a command leads to from `state`; `None` when the command does nothing there.
/// Beyond CiA-402, "enable operation" (15) from Switch on disabled or Ready to switch on goes
/// straight to Operation enabled, as this drive's documentation allows ("6→7→15 or 15
/// directly"). A fault reset only leaves Fault; whether the fault is gone is the caller's
/// check.
pub(super) fn next(state: DriveState, command: Command) -> Option<DriveState> {
    use Command as C;
    use DriveState as S;
    let to = match (state, command) {
        (S::Fault, C::FaultReset) => S::SwitchOnDisabled,
        (S::Fault, _) | (_, C::FaultReset) => return None,
        (S::SwitchOnDisabled, C::Shutdown) => S::ReadyToSwitchOn,
        (S::SwitchOnDisabled | S::ReadyToSwitchOn | S::SwitchedOn, C::EnableOperation) => {
            S::OperationEnabled
        }
        (S::ReadyToSwitchOn, C::SwitchOn) => S::SwitchedOn,
        (S::SwitchedOn | S::OperationEnabled, C::Shutdown) => S::ReadyToSwitchOn,
        (S::OperationEnabled, C::SwitchOn) => S::SwitchedOn,
        (S::OperationEnabled, C::QuickStop) => S::QuickStopActive,
        (S::QuickStopActive, C::EnableOperation) => S::OperationEnabled,
        (
            S::ReadyToSwitchOn | S::SwitchedOn | S::OperationEnabled | S::QuickStopActive,
            C::DisableVoltage,
        )
        | (S::ReadyToSwitchOn | S::SwitchedOn, C::QuickStop) => S::SwitchOnDisabled,
        _ => return None,
    };
    (to != state).then_some(to)
}

/// Statusword bits 0–3, 5 and 6 of a state (CiA-402 table: ready to switch on, switched on,
/// operation enabled, fault, quick stop — set when *not* active — and switch on disabled).
pub(super) fn state_bits(state: DriveState) -> u16 {
    match state {
        DriveState::SwitchOnDisabled => 0x0040,
        DriveState::ReadyToSwitchOn => 0x0021,
        DriveState::SwitchedOn => 0x0023,
        DriveState::OperationEnabled => 0x0027,
        DriveState::QuickStopActive => 0x0007,
        DriveState::Fault => 0x0008,
    }
}

/// Whether the motor is energised in this state.
pub(super) fn energised(state: DriveState) -> bool {
    matches!(
        state,
        DriveState::OperationEnabled | DriveState::QuickStopActive
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use Command as C;
    use DriveState as S;

    #[test]
    fn controlwords_decode_as_cia_402_says() {
        assert_eq!(decode(0x06, 0), C::Shutdown);
        assert_eq!(decode(0x07, 0), C::SwitchOn);
        assert_eq!(decode(0x0F, 0), C::EnableOperation);
        assert_eq!(decode(0x1F, 0), C::EnableOperation);
        assert_eq!(decode(0x01, 0), C::DisableVoltage);
        assert_eq!(decode(0x00, 0), C::DisableVoltage);
        assert_eq!(decode(0x0B, 0), C::QuickStop);
        assert_eq!(decode(0x02, 0), C::QuickStop);
        assert_eq!(decode(0x80, 0), C::FaultReset);
        // Holding bit 7 is not a new reset.
        assert_eq!(decode(0x86, 0x80), C::Shutdown);
    }

    #[test]
    fn the_documented_enable_sequences_reach_operation_enabled() {
        let mut state = S::SwitchOnDisabled;
        for (word, expected) in [
            (6, S::ReadyToSwitchOn),
            (7, S::SwitchedOn),
            (15, S::OperationEnabled),
        ] {
            state = next(state, decode(word, 0)).unwrap();
            assert_eq!(state, expected);
        }
        assert_eq!(
            next(S::SwitchOnDisabled, decode(15, 0)),
            Some(S::OperationEnabled)
        );
        assert_eq!(
            next(S::OperationEnabled, decode(1, 15)),
            Some(S::SwitchOnDisabled)
        );
        assert_eq!(
            next(S::OperationEnabled, decode(11, 15)),
            Some(S::QuickStopActive)
        );
        assert_eq!(
            next(S::QuickStopActive, decode(15, 11)),
            Some(S::OperationEnabled)
        );
        assert_eq!(next(S::QuickStopActive, decode(6, 11)), None);
    }

    #[test]
    fn only_a_fault_reset_leaves_fault() {
        assert_eq!(next(S::Fault, C::EnableOperation), None);
        assert_eq!(next(S::Fault, C::FaultReset), Some(S::SwitchOnDisabled));
        assert_eq!(next(S::OperationEnabled, C::FaultReset), None);
    }

    #[test]
    fn statusword_patterns_match_the_profile() {
        // (mask 0x6F) as masters check them.
        assert_eq!(state_bits(S::ReadyToSwitchOn) & 0x6F, 0x21);
        assert_eq!(state_bits(S::SwitchedOn) & 0x6F, 0x23);
        assert_eq!(state_bits(S::OperationEnabled) & 0x6F, 0x27);
        assert_eq!(state_bits(S::QuickStopActive) & 0x6F, 0x07);
        assert_eq!(state_bits(S::SwitchOnDisabled) & 0x4F, 0x40);
        assert_eq!(state_bits(S::Fault) & 0x4F, 0x08);
    }
}
