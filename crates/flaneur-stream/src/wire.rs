//! Little-endian fields in and out of a message body. The reader never reads past its
//! body and never allocates from a count it has not bounded by the bytes left: each
//! element of a list takes at least `min_len` bytes, so a count larger than the bytes
//! left allow is an error before anything is reserved.

use crate::error::StreamError;

/// Appends fields to a body.
#[derive(Default)]
pub(crate) struct Writer {
    pub(crate) bytes: Vec<u8>,
}

impl Writer {
    pub(crate) fn u8(&mut self, v: u8) {
        self.bytes.push(v);
    }
    pub(crate) fn u16(&mut self, v: u16) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    pub(crate) fn u32(&mut self, v: u32) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    pub(crate) fn u64(&mut self, v: u64) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    pub(crate) fn f32(&mut self, v: f32) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    pub(crate) fn vec3(&mut self, v: [f32; 3]) {
        v.into_iter().for_each(|x| self.f32(x));
    }
    pub(crate) fn raw(&mut self, b: &[u8]) {
        self.bytes.extend_from_slice(b);
    }
    /// A count of a list's elements, which must fit 32 bits (the encoder's lists are
    /// bounded far below that).
    pub(crate) fn count(&mut self, n: usize) {
        self.u32(u32::try_from(n).unwrap_or(u32::MAX));
    }
}

/// Reads fields off a body, naming the message in its errors.
pub(crate) struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    what: &'static str,
}

impl<'a> Reader<'a> {
    pub(crate) fn new(bytes: &'a [u8], what: &'static str) -> Reader<'a> {
        Reader { bytes, at: 0, what }
    }

    pub(crate) fn bad(&self, why: impl std::fmt::Display) -> StreamError {
        StreamError::Malformed(format!("{} at byte {}: {why}", self.what, self.at))
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8], StreamError> {
        let left = self.bytes.len() - self.at;
        if n > left {
            return Err(self.bad(format!("{n} bytes wanted, {left} left")));
        }
        let b = &self.bytes[self.at..self.at + n];
        self.at += n;
        Ok(b)
    }

    pub(crate) fn u8(&mut self) -> Result<u8, StreamError> {
        Ok(self.take(1)?[0])
    }
    pub(crate) fn u16(&mut self) -> Result<u16, StreamError> {
        Ok(u16::from_le_bytes(
            self.take(2)?.try_into().expect("2 bytes"),
        ))
    }
    pub(crate) fn u32(&mut self) -> Result<u32, StreamError> {
        Ok(u32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    pub(crate) fn u64(&mut self) -> Result<u64, StreamError> {
        Ok(u64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    pub(crate) fn f32(&mut self) -> Result<f32, StreamError> {
        Ok(f32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    /// Three floats, each finite.
    pub(crate) fn vec3(&mut self) -> Result<[f32; 3], StreamError> {
        let v = [self.f32()?, self.f32()?, self.f32()?];
        if v.iter().all(|x| x.is_finite()) {
            Ok(v)
        } else {
            Err(self.bad(format!("a vector {v:?} that is not finite")))
        }
    }
    pub(crate) fn raw(&mut self, n: usize) -> Result<&'a [u8], StreamError> {
        self.take(n)
    }

    /// A count of elements of at least `min_len` bytes each, bounded by the bytes left.
    pub(crate) fn count(&mut self, min_len: usize) -> Result<usize, StreamError> {
        let n = self.u32()? as usize;
        let left = self.bytes.len() - self.at;
        if n.saturating_mul(min_len.max(1)) > left {
            return Err(self.bad(format!(
                "a count of {n} elements of at least {min_len} bytes, with {left} bytes left"
            )));
        }
        Ok(n)
    }

    /// Refuses `n` elements of at least `min_len` bytes each (counted earlier) when the
    /// bytes left cannot hold them, before anything is reserved for them.
    pub(crate) fn fits(&self, n: usize, min_len: usize) -> Result<(), StreamError> {
        let left = self.bytes.len() - self.at;
        if n.saturating_mul(min_len.max(1)) > left {
            return Err(self.bad(format!(
                "{n} elements of at least {min_len} bytes, with {left} bytes left"
            )));
        }
        Ok(())
    }

    /// A count as [`Reader::count`] reads it, refused above `max` (`what` names what
    /// is counted).
    pub(crate) fn count_at_most(
        &mut self,
        min_len: usize,
        max: usize,
        what: &str,
    ) -> Result<usize, StreamError> {
        let n = self.count(min_len)?;
        if n > max {
            return Err(self.bad(format!("{n} {what}, above the {max} allowed")));
        }
        Ok(n)
    }

    /// The body is read whole.
    pub(crate) fn end(&self) -> Result<(), StreamError> {
        let left = self.bytes.len() - self.at;
        if left == 0 {
            Ok(())
        } else {
            Err(self.bad(format!("{left} bytes past the message's end")))
        }
    }
}
