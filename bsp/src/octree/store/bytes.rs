//! Little-endian records: a growing byte buffer to write, and a
//! bounds-checked cursor to read that reports where a record failed.

use crate::Error;

/// Bytes being written.
pub(super) struct Writer(pub(super) Vec<u8>);

impl Writer {
    pub(super) fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    pub(super) fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub(super) fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub(super) fn i64(&mut self, v: i64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub(super) fn i128(&mut self, v: i128) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    /// A count or an index. Every count the kernel holds fits: node and
    /// plane indices are `u32` already, and an octree has fewer than 2^32
    /// leaves long before memory runs out.
    pub(super) fn index(&mut self, n: usize) {
        self.u32(u32::try_from(n).unwrap_or(u32::MAX));
    }
}

/// A cursor over the records of a file; `at` is the absolute offset.
pub(super) struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    /// Reads `bytes[at..]`; offsets in errors are into `bytes`.
    pub(super) fn new(bytes: &'a [u8], at: usize) -> Self {
        Self { bytes, at }
    }

    /// The offset of the next byte.
    pub(super) fn at(&self) -> usize {
        self.at
    }

    /// Bytes left to read.
    pub(super) fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.at)
    }

    /// A malformed record starting at `at`.
    pub(super) fn corrupt(at: usize, reason: &'static str) -> Error {
        Error::CorruptFile { at, reason }
    }

    fn take<const N: usize>(&mut self) -> Result<[u8; N], Error> {
        let slice = self
            .at
            .checked_add(N)
            .and_then(|end| self.bytes.get(self.at..end))
            .ok_or(Error::TruncatedFile {
                at: self.bytes.len(),
            })?;
        let mut out = [0u8; N];
        out.copy_from_slice(slice);
        self.at += N;
        Ok(out)
    }

    pub(super) fn u8(&mut self) -> Result<u8, Error> {
        Ok(self.take::<1>()?[0])
    }
    pub(super) fn u32(&mut self) -> Result<u32, Error> {
        Ok(u32::from_le_bytes(self.take()?))
    }
    pub(super) fn u64(&mut self) -> Result<u64, Error> {
        Ok(u64::from_le_bytes(self.take()?))
    }
    pub(super) fn i64(&mut self) -> Result<i64, Error> {
        Ok(i64::from_le_bytes(self.take()?))
    }
    pub(super) fn i128(&mut self) -> Result<i128, Error> {
        Ok(i128::from_le_bytes(self.take()?))
    }

    /// A count of records of at least `record_bytes` bytes each, refused
    /// when the rest of the file cannot hold that many (so that a damaged
    /// count never allocates more than the file's size).
    pub(super) fn count(&mut self, record_bytes: usize) -> Result<usize, Error> {
        let at = self.at;
        let n = self.u32()? as usize;
        if n.saturating_mul(record_bytes) > self.remaining() {
            return Err(Self::corrupt(
                at,
                "a count of records larger than the rest of the file",
            ));
        }
        Ok(n)
    }
}
