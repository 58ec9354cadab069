//! A small hand-written little-endian binary codec for the persisted state
//! ([`IncrementalState::to_bytes`](crate::IncrementalState::to_bytes),
//! [`ConditionModel::to_bytes`](crate::ConditionModel::to_bytes)).
//!
//! Layout of every encoded value: an 8-byte magic naming the type, a `u32` format version,
//! then the fields in a fixed order (integers little-endian, `f64` as their IEEE-754 bits,
//! lengths as `u64`). Encoding is deterministic: equal values give equal bytes. Decoding never
//! panics and never allocates more than the input could describe: every length is checked
//! against the bytes left before anything is reserved.

use crate::UtilityError;

/// Appends fields to a byte buffer.
#[derive(Debug, Default)]
pub(crate) struct Writer {
    pub(crate) buf: Vec<u8>,
}

impl Writer {
    /// A buffer starting with `magic` and `version`.
    pub(crate) fn with_header(magic: &[u8; 8], version: u32) -> Self {
        let mut w = Self { buf: Vec::new() };
        w.buf.extend_from_slice(magic);
        w.u32(version);
        w
    }
    pub(crate) fn u8(&mut self, v: u8) {
        self.buf.push(v);
    }
    pub(crate) fn bool(&mut self, v: bool) {
        self.u8(u8::from(v));
    }
    pub(crate) fn u32(&mut self, v: u32) {
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    pub(crate) fn u64(&mut self, v: u64) {
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    pub(crate) fn len(&mut self, v: usize) {
        self.u64(v as u64);
    }
    pub(crate) fn i64(&mut self, v: i64) {
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    pub(crate) fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    pub(crate) fn opt_i64(&mut self, v: Option<i64>) {
        match v {
            Some(x) => {
                self.u8(1);
                self.i64(x);
            }
            None => self.u8(0),
        }
    }
    pub(crate) fn f64s(&mut self, v: &[f64]) {
        self.len(v.len());
        for &x in v {
            self.f64(x);
        }
    }
    pub(crate) fn i64s(&mut self, v: &[i64]) {
        self.len(v.len());
        for &x in v {
            self.i64(x);
        }
    }
}

/// Reads fields back, failing with [`UtilityError::Decode`] on truncated or invalid input.
#[derive(Debug)]
pub(crate) struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
    what: &'static str,
}

impl<'a> Reader<'a> {
    /// Checks the magic and the version (must be in `versions`); returns the reader positioned
    /// after the header and the version found.
    pub(crate) fn with_header(
        bytes: &'a [u8],
        magic: &[u8; 8],
        versions: std::ops::RangeInclusive<u32>,
        what: &'static str,
    ) -> Result<(Self, u32), UtilityError> {
        let mut r = Self {
            bytes,
            pos: 0,
            what,
        };
        let m = r.take(8)?;
        if m != magic {
            return Err(r.error(format!(
                "bad magic {m:02x?} (expected {magic:02x?}): not a serialised {what}"
            )));
        }
        let v = r.u32()?;
        if !versions.contains(&v) {
            return Err(r.error(format!(
                "format version {v} not supported (supported: {}..={})",
                versions.start(),
                versions.end()
            )));
        }
        Ok((r, v))
    }

    pub(crate) fn error(&self, reason: String) -> UtilityError {
        UtilityError::Decode {
            what: self.what,
            offset: self.pos,
            reason,
        }
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8], UtilityError> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.bytes.len());
        match end {
            Some(end) => {
                let s = &self.bytes[self.pos..end];
                self.pos = end;
                Ok(s)
            }
            None => Err(self.error(format!(
                "truncated: {n} more bytes needed, {} left",
                self.bytes.len() - self.pos
            ))),
        }
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], UtilityError> {
        let s = self.take(N)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }

    pub(crate) fn u8(&mut self) -> Result<u8, UtilityError> {
        Ok(self.array::<1>()?[0])
    }
    pub(crate) fn bool(&mut self) -> Result<bool, UtilityError> {
        match self.u8()? {
            0 => Ok(false),
            1 => Ok(true),
            b => Err(self.error(format!("invalid boolean byte {b}"))),
        }
    }
    pub(crate) fn u32(&mut self) -> Result<u32, UtilityError> {
        Ok(u32::from_le_bytes(self.array()?))
    }
    pub(crate) fn u64(&mut self) -> Result<u64, UtilityError> {
        Ok(u64::from_le_bytes(self.array()?))
    }
    pub(crate) fn i64(&mut self) -> Result<i64, UtilityError> {
        Ok(i64::from_le_bytes(self.array()?))
    }
    pub(crate) fn f64(&mut self) -> Result<f64, UtilityError> {
        Ok(f64::from_bits(self.u64()?))
    }
    /// A finite `f64`.
    pub(crate) fn finite(&mut self) -> Result<f64, UtilityError> {
        let v = self.f64()?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.error(format!("non-finite value {v}")))
        }
    }
    pub(crate) fn opt_i64(&mut self) -> Result<Option<i64>, UtilityError> {
        match self.u8()? {
            0 => Ok(None),
            1 => Ok(Some(self.i64()?)),
            b => Err(self.error(format!("invalid option tag {b}"))),
        }
    }
    /// A length whose elements take at least `min_element_bytes` each: larger than the bytes
    /// left could hold is an error (so corrupt lengths never cause huge allocations).
    pub(crate) fn len(&mut self, min_element_bytes: usize) -> Result<usize, UtilityError> {
        let n = self.u64()?;
        let left = (self.bytes.len() - self.pos) as u64;
        if n.saturating_mul(min_element_bytes.max(1) as u64) > left {
            return Err(self.error(format!("length {n} exceeds the {left} bytes left")));
        }
        usize::try_from(n).map_err(|_| self.error(format!("length {n} too large")))
    }
    pub(crate) fn f64s(&mut self) -> Result<Vec<f64>, UtilityError> {
        let n = self.len(8)?;
        (0..n).map(|_| self.f64()).collect()
    }
    pub(crate) fn finite_f64s(&mut self) -> Result<Vec<f64>, UtilityError> {
        let n = self.len(8)?;
        (0..n).map(|_| self.finite()).collect()
    }
    pub(crate) fn i64s(&mut self) -> Result<Vec<i64>, UtilityError> {
        let n = self.len(8)?;
        (0..n).map(|_| self.i64()).collect()
    }
    /// Bytes not read yet.
    pub(crate) fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }
    /// Fails unless every byte was consumed.
    pub(crate) fn finish(self) -> Result<(), UtilityError> {
        if self.pos == self.bytes.len() {
            Ok(())
        } else {
            Err(self.error(format!("{} trailing bytes", self.bytes.len() - self.pos)))
        }
    }
}
