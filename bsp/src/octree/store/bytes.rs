//! Little-endian records: a growing byte buffer to write, and a
//! bounds-checked cursor to read that reports where a record failed.
//!
//! Octree files use them, and so can other file formats built on the
//! kernel (the plugin's terrain files do). Reading never panics: a value
//! that runs past the end is [`ReadError::Truncated`], and a count of
//! records that the bytes left cannot hold is [`ReadError::CountTooLarge`],
//! caught before anything is allocated for it. Each file format turns
//! these into its own error type (for octree files, [`Error`] through
//! `From`).

use core::fmt;

use crate::Error;

/// Bytes being written, each value little-endian.
#[derive(Clone, Debug, Default)]
pub struct Writer {
    bytes: Vec<u8>,
}

impl Writer {
    /// An empty buffer.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends `bytes` as they are (a magic, or a record written
    /// elsewhere).
    pub fn bytes(&mut self, bytes: &[u8]) {
        self.bytes.extend_from_slice(bytes);
    }
    /// Appends one byte.
    pub fn u8(&mut self, v: u8) {
        self.bytes.push(v);
    }
    /// Appends a `u32`.
    pub fn u32(&mut self, v: u32) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    /// Appends a `u64`.
    pub fn u64(&mut self, v: u64) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    /// Appends an `i64`.
    pub fn i64(&mut self, v: i64) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    /// Appends an `i128`.
    pub fn i128(&mut self, v: i128) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    /// Appends a count or an index as a `u32` (`u32::MAX` above that).
    /// Every count the kernel holds fits: node and plane indices are `u32`
    /// already, and an octree has fewer than 2^32 leaves long before
    /// memory runs out.
    pub fn count(&mut self, n: usize) {
        self.u32(u32::try_from(n).unwrap_or(u32::MAX));
    }

    /// Replaces the bytes from offset `at` with `bytes`: for a length or a
    /// count written as a placeholder before it was known.
    ///
    /// # Panics
    /// When `at + bytes.len()` is past the bytes written so far (a bug in
    /// the writer, never a property of data read).
    pub fn overwrite(&mut self, at: usize, bytes: &[u8]) {
        self.bytes[at..at + bytes.len()].copy_from_slice(bytes);
    }

    /// The bytes written so far.
    #[must_use]
    pub fn as_bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// The bytes written.
    #[must_use]
    pub fn into_bytes(self) -> Vec<u8> {
        self.bytes
    }
}

/// Why a [`Reader`] could not read a value.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ReadError {
    /// The bytes end before the value that starts at offset `at` does:
    /// the bytes were cut short.
    Truncated {
        /// Offset of the value that could not be read.
        at: usize,
        /// Offset where the bytes end.
        end: usize,
    },
    /// A count of records, read at offset `at`, larger than the bytes
    /// left can hold: a damaged count, refused before anything is
    /// allocated for it.
    CountTooLarge {
        /// Offset of the count.
        at: usize,
        /// The count read.
        count: usize,
    },
}

impl fmt::Display for ReadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ReadError::Truncated { at, end } => write!(
                f,
                "the bytes end at {end}, before the value at byte {at}; they were cut short"
            ),
            ReadError::CountTooLarge { at, count } => write!(
                f,
                "a count of {count} records at byte {at} is larger than the rest of the bytes"
            ),
        }
    }
}

impl std::error::Error for ReadError {}

impl From<ReadError> for Error {
    fn from(e: ReadError) -> Self {
        match e {
            ReadError::Truncated { end, .. } => Error::TruncatedFile { at: end },
            ReadError::CountTooLarge { at, .. } => Error::CorruptFile {
                at,
                reason: "a count of records larger than the rest of the file",
            },
        }
    }
}

/// A cursor over little-endian records; offsets, in errors too, are into
/// the whole slice it reads.
#[derive(Clone, Debug)]
pub struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    /// Reads `bytes[at..]`; offsets in errors are into `bytes`.
    #[must_use]
    pub fn new(bytes: &'a [u8], at: usize) -> Self {
        Self { bytes, at }
    }

    /// The offset of the next byte.
    #[must_use]
    pub fn at(&self) -> usize {
        self.at
    }

    /// Bytes left to read.
    #[must_use]
    pub fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.at)
    }

    /// A malformed octree file record starting at `at`.
    pub(crate) fn corrupt(at: usize, reason: &'static str) -> Error {
        Error::CorruptFile { at, reason }
    }

    /// The next `n` bytes as they are.
    ///
    /// # Errors
    /// [`ReadError::Truncated`] when fewer than `n` are left.
    pub fn bytes(&mut self, n: usize) -> Result<&'a [u8], ReadError> {
        let slice = self
            .at
            .checked_add(n)
            .and_then(|end| self.bytes.get(self.at..end))
            .ok_or(ReadError::Truncated {
                at: self.at,
                end: self.bytes.len(),
            })?;
        self.at += n;
        Ok(slice)
    }

    fn take<const N: usize>(&mut self) -> Result<[u8; N], ReadError> {
        let mut out = [0u8; N];
        out.copy_from_slice(self.bytes(N)?);
        Ok(out)
    }

    /// The next byte.
    ///
    /// # Errors
    /// [`ReadError::Truncated`] at the end of the bytes.
    pub fn u8(&mut self) -> Result<u8, ReadError> {
        Ok(self.take::<1>()?[0])
    }
    /// The next `u32`.
    ///
    /// # Errors
    /// [`ReadError::Truncated`] when fewer than 4 bytes are left.
    pub fn u32(&mut self) -> Result<u32, ReadError> {
        Ok(u32::from_le_bytes(self.take()?))
    }
    /// The next `u64`.
    ///
    /// # Errors
    /// [`ReadError::Truncated`] when fewer than 8 bytes are left.
    pub fn u64(&mut self) -> Result<u64, ReadError> {
        Ok(u64::from_le_bytes(self.take()?))
    }
    /// The next `i64`.
    ///
    /// # Errors
    /// [`ReadError::Truncated`] when fewer than 8 bytes are left.
    pub fn i64(&mut self) -> Result<i64, ReadError> {
        Ok(i64::from_le_bytes(self.take()?))
    }
    /// The next `i128`.
    ///
    /// # Errors
    /// [`ReadError::Truncated`] when fewer than 16 bytes are left.
    pub fn i128(&mut self) -> Result<i128, ReadError> {
        Ok(i128::from_le_bytes(self.take()?))
    }

    /// A count (a `u32`, as [`Writer::count`] writes it) of records of at
    /// least `record_bytes` bytes each.
    ///
    /// # Errors
    /// [`ReadError::CountTooLarge`] when the rest of the bytes cannot hold
    /// that many, so that a damaged count never allocates more than the
    /// bytes' size; [`ReadError::Truncated`] when the count itself is cut
    /// short.
    pub fn count(&mut self, record_bytes: usize) -> Result<usize, ReadError> {
        let at = self.at;
        let count = self.u32()? as usize;
        if count.saturating_mul(record_bytes) > self.remaining() {
            return Err(ReadError::CountTooLarge { at, count });
        }
        Ok(count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_value_reads_back_as_written() {
        let mut w = Writer::new();
        w.bytes(b"AB");
        w.u8(7);
        w.u32(0xDEAD_BEEF);
        w.u64(u64::MAX - 1);
        w.i64(-5);
        w.i128(i128::MIN + 3);
        w.count(2);
        w.overwrite(0, b"Z");
        let bytes = w.into_bytes();
        assert_eq!(bytes.len(), 2 + 1 + 4 + 8 + 8 + 16 + 4);
        let mut r = Reader::new(&bytes, 0);
        assert_eq!(r.bytes(2), Ok(&b"ZB"[..]));
        assert_eq!(r.u8(), Ok(7));
        assert_eq!(r.u32(), Ok(0xDEAD_BEEF));
        assert_eq!(r.u64(), Ok(u64::MAX - 1));
        assert_eq!(r.i64(), Ok(-5));
        assert_eq!(r.i128(), Ok(i128::MIN + 3));
        assert_eq!(r.u32(), Ok(2));
        assert_eq!((r.at(), r.remaining()), (bytes.len(), 0));
    }

    #[test]
    fn a_value_past_the_end_is_truncated_and_reads_nothing() {
        let bytes = [1u8, 2, 3];
        let mut r = Reader::new(&bytes, 1);
        assert_eq!(r.u32(), Err(ReadError::Truncated { at: 1, end: 3 }));
        assert_eq!(r.at(), 1);
        assert_eq!(
            r.bytes(usize::MAX),
            Err(ReadError::Truncated { at: 1, end: 3 })
        );
        assert_eq!(r.u8(), Ok(2));
        // A reader placed past the end fails without panicking.
        let mut past = Reader::new(&bytes, 10);
        assert_eq!(past.remaining(), 0);
        assert_eq!(past.u8(), Err(ReadError::Truncated { at: 10, end: 3 }));
        assert_eq!(
            Error::from(ReadError::Truncated { at: 1, end: 3 }),
            Error::TruncatedFile { at: 3 }
        );
    }

    #[test]
    fn a_count_the_rest_cannot_hold_is_refused() {
        let mut w = Writer::new();
        w.count(3);
        w.bytes(&[0; 6]);
        let bytes = w.into_bytes();
        assert_eq!(Reader::new(&bytes, 0).count(2), Ok(3));
        assert_eq!(
            Reader::new(&bytes, 0).count(3),
            Err(ReadError::CountTooLarge { at: 0, count: 3 })
        );
        let huge = u32::MAX.to_le_bytes();
        assert_eq!(
            Reader::new(&huge, 0).count(usize::MAX),
            Err(ReadError::CountTooLarge {
                at: 0,
                count: u32::MAX as usize
            })
        );
        assert!(matches!(
            Error::from(ReadError::CountTooLarge { at: 4, count: 9 }),
            Error::CorruptFile { at: 4, .. }
        ));
    }
}
