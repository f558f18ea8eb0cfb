//! CiA-301 network management as a slave sees it: the NMT states, the master's commands
//! (COB-ID 0x000) and the error-control frames (boot-up and heartbeat on 0x700 + node-ID).

/// COB-ID of NMT commands from the master.
pub(super) const NMT_COB_ID: u16 = 0x000;
/// Base of the error-control COB-ID (boot-up, heartbeat): 0x700 + node-ID.
pub(super) const ERROR_CONTROL_BASE: u16 = 0x700;

/// The NMT state of the node.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum NmtState {
    /// Powered on, boot-up not sent yet (the first millisecond).
    Initialising,
    /// SDO and NMT served, no PDOs (the state after boot-up).
    PreOperational,
    /// Everything served.
    Operational,
    /// Only NMT and heartbeats: SDO requests go unanswered (CiA-301).
    Stopped,
}

impl NmtState {
    /// The state byte of a heartbeat frame (boot-up is the separate 0x00).
    pub(super) fn heartbeat_byte(self) -> u8 {
        match self {
            NmtState::Initialising => 0x00,
            NmtState::Stopped => 0x04,
            NmtState::Operational => 0x05,
            NmtState::PreOperational => 0x7F,
        }
    }

    /// Whether the SDO server answers in this state.
    pub(super) fn serves_sdo(self) -> bool {
        matches!(self, NmtState::PreOperational | NmtState::Operational)
    }
}

/// A command specifier of an NMT frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum NmtCommand {
    /// 0x01: go to Operational.
    Start,
    /// 0x02: go to Stopped.
    Stop,
    /// 0x80: go to Pre-operational.
    EnterPreOperational,
    /// 0x81: re-initialise the application and communication, then boot up again.
    ResetNode,
    /// 0x82: re-initialise communication parameters, then boot up again.
    ResetCommunication,
}

/// Decode an NMT frame `[cs, node]` meant for `node_id` (node 0 addresses every node).
/// `None` for another node, a short frame or an unknown command specifier (CiA-301 has no
/// answer to NMT commands, so these are ignored).
pub(super) fn decode(data: &[u8], node_id: u8) -> Option<NmtCommand> {
    let [cs, target, ..] = *data else {
        return None;
    };
    if target != 0 && target != node_id {
        return None;
    }
    match cs {
        0x01 => Some(NmtCommand::Start),
        0x02 => Some(NmtCommand::Stop),
        0x80 => Some(NmtCommand::EnterPreOperational),
        0x81 => Some(NmtCommand::ResetNode),
        0x82 => Some(NmtCommand::ResetCommunication),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_reach_their_node_or_all_nodes() {
        assert_eq!(decode(&[0x01, 5], 5), Some(NmtCommand::Start));
        assert_eq!(decode(&[0x02, 0], 5), Some(NmtCommand::Stop));
        assert_eq!(decode(&[0x81, 0], 9), Some(NmtCommand::ResetNode));
        assert_eq!(decode(&[0x01, 6], 5), None);
        assert_eq!(decode(&[0x03, 5], 5), None);
        assert_eq!(decode(&[0x01], 5), None);
    }

    #[test]
    fn heartbeat_bytes_follow_cia_301() {
        assert_eq!(NmtState::Stopped.heartbeat_byte(), 0x04);
        assert_eq!(NmtState::Operational.heartbeat_byte(), 0x05);
        assert_eq!(NmtState::PreOperational.heartbeat_byte(), 0x7F);
        assert!(!NmtState::Stopped.serves_sdo());
    }
}
