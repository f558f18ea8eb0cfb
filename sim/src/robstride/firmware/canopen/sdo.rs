//! The SDO server's wire format (CiA-301): expedited upload and download, and the abort
//! frame. Segmented and block transfers are not served: every object of this node fits in
//! four bytes, so they are answered with an abort. Every object is readable, so "read of a
//! write-only object" (0x06010001) never occurs.

/// Base of the client→server COB-ID: 0x600 + node-ID.
pub(super) const RX_BASE: u16 = 0x600;
/// Base of the server→client COB-ID: 0x580 + node-ID.
pub(super) const TX_BASE: u16 = 0x580;

/// An object address: index and subindex.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Address {
    /// Index (0x1000..0x6FFF here).
    pub index: u16,
    /// Subindex.
    pub sub: u8,
}

/// The CiA-301 abort codes this server sends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Abort {
    /// 0x05040001: client/server command specifier not valid or unknown (also segmented and
    /// block transfers, which are not served).
    CommandInvalid,
    /// 0x06010002: attempt to write a read-only object.
    WriteOfReadOnly,
    /// 0x06020000: object does not exist in the object dictionary.
    NoObject,
    /// 0x06070010: data type does not match, length of service parameter does not match.
    LengthMismatch,
    /// 0x06090011: subindex does not exist.
    NoSubindex,
    /// 0x06090030: invalid value for parameter (value range exceeded).
    ValueRange,
    /// 0x08000022: data cannot be transferred because of the present device state.
    DeviceState,
}

impl Abort {
    /// The 32-bit abort code.
    pub(super) fn code(self) -> u32 {
        match self {
            Abort::CommandInvalid => 0x0504_0001,
            Abort::WriteOfReadOnly => 0x0601_0002,
            Abort::NoObject => 0x0602_0000,
            Abort::LengthMismatch => 0x0607_0010,
            Abort::NoSubindex => 0x0609_0011,
            Abort::ValueRange => 0x0609_0030,
            Abort::DeviceState => 0x0800_0022,
        }
    }
}

/// A client request, decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Request {
    /// Initiate upload (read).
    Upload(Address),
    /// Expedited download (write): up to four data bytes, and the size the client stated
    /// (`None` when the size indicator is clear).
    Download {
        /// Where.
        at: Address,
        /// Bytes 4..7 of the request.
        data: [u8; 4],
        /// Number of meaningful bytes, if stated.
        size: Option<usize>,
    },
    /// Initiate download of a segmented transfer; `size` is the stated total, if any.
    SegmentedDownload {
        /// Where.
        at: Address,
        /// The total size the client announced.
        size: Option<u32>,
    },
    /// The client aborts a transfer (never answered).
    ClientAbort,
    /// A command this server does not serve (segments without a transfer, block transfers,
    /// unknown specifiers, frames shorter than 8 bytes): answered with
    /// [`Abort::CommandInvalid`].
    Unsupported(Address),
}

/// Decode the 8 data bytes of a client request.
pub(super) fn parse(data: &[u8]) -> Request {
    let mut bytes = [0u8; 8];
    let len = data.len().min(8);
    bytes[..len].copy_from_slice(&data[..len]);
    let at = Address {
        index: u16::from_le_bytes([bytes[1], bytes[2]]),
        sub: bytes[3],
    };
    // CiA-301 SDO frames always carry 8 bytes.
    if data.len() != 8 {
        return Request::Unsupported(at);
    }
    let command = bytes[0];
    let payload = [bytes[4], bytes[5], bytes[6], bytes[7]];
    match command >> 5 {
        1 => {
            let expedited = command & 0x02 != 0;
            let size_indicated = command & 0x01 != 0;
            if expedited {
                let unused = usize::from((command >> 2) & 0x03);
                Request::Download {
                    at,
                    data: payload,
                    size: size_indicated.then_some(4 - unused),
                }
            } else {
                Request::SegmentedDownload {
                    at,
                    size: size_indicated.then_some(u32::from_le_bytes(payload)),
                }
            }
        }
        2 => Request::Upload(at),
        4 => Request::ClientAbort,
        _ => Request::Unsupported(at),
    }
}

/// An expedited upload response carrying `value` (1 to 4 bytes, little-endian).
pub(super) fn upload_response(at: Address, value: &[u8]) -> [u8; 8] {
    let size = value.len().clamp(1, 4);
    // scs 2, n = unused bytes, e = 1, s = 1.
    let command = 0x43 | (((4 - size) as u8) << 2);
    let mut out = header(command, at);
    out[4..4 + size].copy_from_slice(&value[..size]);
    out
}

/// The confirmation of a download (scs 3).
pub(super) fn download_response(at: Address) -> [u8; 8] {
    header(0x60, at)
}

/// An abort frame.
pub(super) fn abort(at: Address, why: Abort) -> [u8; 8] {
    let mut out = header(0x80, at);
    out[4..].copy_from_slice(&why.code().to_le_bytes());
    out
}

fn header(command: u8, at: Address) -> [u8; 8] {
    let [lo, hi] = at.index.to_le_bytes();
    [command, lo, hi, at.sub, 0, 0, 0, 0]
}

#[cfg(test)]
mod tests {
    use super::*;

    const STATUSWORD: Address = Address {
        index: 0x6041,
        sub: 0,
    };

    #[test]
    fn requests_decode_by_command_specifier() {
        assert_eq!(
            parse(&[0x40, 0x41, 0x60, 0, 0, 0, 0, 0]),
            Request::Upload(STATUSWORD)
        );
        // 0x2B: expedited, size indicated, 2 bytes.
        assert_eq!(
            parse(&[0x2B, 0x40, 0x60, 0, 0x0F, 0, 0, 0]),
            Request::Download {
                at: Address {
                    index: 0x6040,
                    sub: 0
                },
                data: [0x0F, 0, 0, 0],
                size: Some(2),
            }
        );
        // 0x22: expedited, size not indicated.
        assert!(matches!(
            parse(&[0x22, 0x40, 0x60, 0, 6, 0, 0, 0]),
            Request::Download { size: None, .. }
        ));
        assert_eq!(
            parse(&[0x21, 0x08, 0x10, 0, 20, 0, 0, 0]),
            Request::SegmentedDownload {
                at: Address {
                    index: 0x1008,
                    sub: 0
                },
                size: Some(20)
            }
        );
        assert_eq!(parse(&[0x80, 0, 0, 0, 0, 0, 0, 0]), Request::ClientAbort);
        assert!(matches!(
            parse(&[0x60, 0, 0, 0, 0, 0, 0, 0]),
            Request::Unsupported(_)
        ));
        assert!(matches!(
            parse(&[0xA0, 0x41, 0x60, 0, 0, 0, 0, 0]),
            Request::Unsupported(_)
        ));
        assert!(matches!(
            parse(&[0x40, 0x41, 0x60]),
            Request::Unsupported(_)
        ));
    }

    #[test]
    fn responses_follow_cia_301() {
        assert_eq!(
            upload_response(STATUSWORD, &[0x37, 0x02]),
            [0x4B, 0x41, 0x60, 0, 0x37, 0x02, 0, 0]
        );
        assert_eq!(upload_response(STATUSWORD, &[1])[0], 0x4F);
        assert_eq!(upload_response(STATUSWORD, &[1, 2, 3, 4])[0], 0x43);
        assert_eq!(
            download_response(STATUSWORD),
            [0x60, 0x41, 0x60, 0, 0, 0, 0, 0]
        );
        assert_eq!(
            abort(STATUSWORD, Abort::WriteOfReadOnly),
            [0x80, 0x41, 0x60, 0, 0x02, 0x00, 0x01, 0x06]
        );
    }
}
