//! Reading structured operations out of the fuzzer's flat byte string.

use bus::CanFrame;

/// A cursor over the input. Reads past the end yield nothing, so every input is a valid
/// (possibly short) program.
pub(crate) struct Input<'a> {
    data: &'a [u8],
}

impl<'a> Input<'a> {
    pub(crate) fn new(data: &'a [u8]) -> Self {
        Self { data }
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    pub(crate) fn byte(&mut self) -> Option<u8> {
        let (&first, rest) = self.data.split_first()?;
        self.data = rest;
        Some(first)
    }

    /// Up to `n` bytes (fewer at the end of the input).
    pub(crate) fn take(&mut self, n: usize) -> &'a [u8] {
        let (head, rest) = self.data.split_at(n.min(self.data.len()));
        self.data = rest;
        head
    }

    pub(crate) fn u16(&mut self) -> u16 {
        let b = self.take(2);
        u16::from_be_bytes([
            b.first().copied().unwrap_or(0),
            b.get(1).copied().unwrap_or(0),
        ])
    }

    pub(crate) fn u32(&mut self) -> u32 {
        let b = self.take(4);
        let mut w = [0u8; 4];
        w[..b.len()].copy_from_slice(b);
        u32::from_be_bytes(w)
    }

    /// A data length code (0..=8) and that many bytes (zero-padded at the end of the input).
    pub(crate) fn payload(&mut self) -> Vec<u8> {
        let len = usize::from(self.byte().unwrap_or(8) % 9);
        let mut data = self.take(len).to_vec();
        data.resize(len, 0);
        data
    }
}

/// A standard frame with `id` masked to 11 bits (always valid).
pub(crate) fn standard(id: u16, data: &[u8]) -> CanFrame {
    CanFrame::standard(id & 0x7FF, data).expect("11-bit id and at most 8 bytes")
}

/// An extended frame with `id` masked to 29 bits (always valid).
pub(crate) fn extended(id: u32, data: &[u8]) -> CanFrame {
    CanFrame::extended(id & 0x1FFF_FFFF, data).expect("29-bit id and at most 8 bytes")
}

/// Panics unless every value is finite, naming the first that is not.
pub(crate) fn assert_finite<'v>(what: &str, values: impl IntoIterator<Item = &'v f64>) {
    for (i, v) in values.into_iter().enumerate() {
        assert!(v.is_finite(), "{what}[{i}] is not finite: {v}");
    }
}
