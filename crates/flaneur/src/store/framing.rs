//! What the byte formats stored in extents share — the LOD chain, progressive mesh, DAG
//! and table (`lod`), and the visibility table (`visibility`): little-endian reads, and
//! the frame each of them checks before its content (a four-byte magic at offset 0, a
//! u32 version at offset 4, a length the header's counts fix, a crc32 of the bytes
//! before the stored one). One copy of each, so that they all read alike and name the
//! same fault in the same words.
//!
//! A check returns its fault as a `String`; each codec wraps it in its own `corrupt`,
//! which names the format. Each format's layout and content checks stay in its module.

use std::fmt::Display;

/// Bytes of a stored crc32.
pub(crate) const CRC_LEN: usize = 4;

/// Bytes of the magic every format starts with; its version follows.
const MAGIC_LEN: usize = 4;

pub(crate) fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

pub(crate) fn u64_at(b: &[u8], at: usize) -> u64 {
    let mut w = [0u8; 8];
    w.copy_from_slice(&b[at..at + 8]);
    u64::from_le_bytes(w)
}

pub(crate) fn f64_at(b: &[u8], at: usize) -> f64 {
    f64::from_bits(u64_at(b, at))
}

pub(crate) fn f32_at(b: &[u8], at: usize) -> f32 {
    f32::from_bits(u32_at(b, at))
}

/// Appends the crc32 of every byte of `b` so far.
pub(crate) fn push_crc(b: &mut Vec<u8>) {
    let crc = crc32fast::hash(b);
    b.extend_from_slice(&crc.to_le_bytes());
}

/// The fixed header: at least `header_len` bytes (8 or more), then
/// [`magic_and_version`].
pub(crate) fn header(
    b: &[u8],
    header_len: usize,
    name: &str,
    magic: [u8; 4],
    version: u32,
) -> Result<(), String> {
    at_least(b.len(), header_len as u64, "the header alone takes")?;
    magic_and_version(b, name, magic, version)
}

/// The magic, then the version, of bytes that hold at least 8. `name` is what the
/// bytes should be ("a DAG").
pub(crate) fn magic_and_version(
    b: &[u8],
    name: &str,
    magic: [u8; 4],
    version: u32,
) -> Result<(), String> {
    if b[..MAGIC_LEN] != magic {
        return Err(format!("not {name} (bad magic)"));
    }
    let stored = u32_at(b, MAGIC_LEN);
    if stored != version {
        return Err(format!(
            "version {stored}, this build reads version {version}"
        ));
    }
    Ok(())
}

/// `len` bytes where `need` are due, at least: `takes` says what takes them ("its
/// counts take").
pub(crate) fn at_least(len: usize, need: u64, takes: impl Display) -> Result<(), String> {
    if (len as u64) < need {
        return Err(format!("truncated: {len} bytes, {takes} {need}"));
    }
    Ok(())
}

/// `len` bytes where exactly `need` are due: truncated as [`at_least`] says, or
/// trailing bytes.
pub(crate) fn exactly(len: usize, need: u64, takes: impl Display) -> Result<(), String> {
    at_least(len, need, &takes)?;
    if len as u64 > need {
        return Err(format!("{len} bytes, {takes} {need}: trailing bytes"));
    }
    Ok(())
}

/// The crc32 stored at `crc_at` against that of every byte before it.
pub(crate) fn checksum(b: &[u8], crc_at: usize) -> Result<(), String> {
    crc_matches(u32_at(b, crc_at), &b[..crc_at])
}

/// A crc32 `stored` elsewhere against that of `bytes`.
pub(crate) fn crc_matches(stored: u32, bytes: &[u8]) -> Result<(), String> {
    let actual = crc32fast::hash(bytes);
    if stored != actual {
        return Err(format!(
            "checksum mismatch (stored {stored:08x}, computed {actual:08x})"
        ));
    }
    Ok(())
}

/// Appends `v` as a LEB128 varint: seven bits a byte, low first, the top bit set on
/// every byte but the last.
pub(crate) fn push_varint(b: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        b.push(v as u8 | 0x80);
        v >>= 7;
    }
    b.push(v as u8);
}

/// The varint at `*at`, moving `*at` past it; `None` when the bytes end inside it or it
/// holds more than 64 bits.
pub(crate) fn read_varint(b: &[u8], at: &mut usize) -> Option<u64> {
    let mut v = 0u64;
    for shift in (0..64).step_by(7) {
        let byte = *b.get(*at)?;
        *at += 1;
        // The tenth byte holds bit 63 alone: more would be dropped, not read.
        if shift == 63 && byte & 0x7f > 1 {
            return None;
        }
        v |= ((byte & 0x7f) as u64) << shift;
        if byte & 0x80 == 0 {
            return Some(v);
        }
    }
    None
}

/// A signed value as an unsigned one whose small magnitudes stay small (0, -1, 1, -2 …
/// as 0, 1, 2, 3 …), for a varint.
pub(crate) fn zigzag(v: i64) -> u64 {
    ((v << 1) ^ (v >> 63)) as u64
}

/// The inverse of [`zigzag`].
pub(crate) fn unzigzag(v: u64) -> i64 {
    (v >> 1) as i64 ^ -((v & 1) as i64)
}

/// Reads a body of varints and fixed-width fields front to back. Each read names the
/// section it is for, so that bytes that end early, or a varint too large for its
/// field, are named where they fail.
pub(crate) struct Cursor<'a> {
    b: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    pub(crate) fn new(b: &'a [u8]) -> Cursor<'a> {
        Cursor { b, at: 0 }
    }

    /// The next varint, at most `max`.
    pub(crate) fn varint(&mut self, max: u64, what: &str) -> Result<u64, String> {
        let v = read_varint(self.b, &mut self.at)
            .ok_or_else(|| format!("{what}: the bytes end inside a varint, or it overflows"))?;
        if v > max {
            return Err(format!("{what}: {v} is past {max}"));
        }
        Ok(v)
    }

    /// The next varint as a u32.
    pub(crate) fn u32(&mut self, what: &str) -> Result<u32, String> {
        self.varint(u32::MAX as u64, what).map(|v| v as u32)
    }

    /// The next zigzag varint as an i32.
    pub(crate) fn i32(&mut self, what: &str) -> Result<i32, String> {
        let v = unzigzag(self.varint(u64::MAX, what)?);
        i32::try_from(v).map_err(|_| format!("{what}: {v} is past 32 bits"))
    }

    /// The next `n` bytes.
    pub(crate) fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&e| e <= self.b.len())
            .ok_or_else(|| {
                format!(
                    "{what}: truncated, {} bytes left where {n} are due",
                    self.b.len() - self.at
                )
            })?;
        let s = &self.b[self.at..end];
        self.at = end;
        Ok(s)
    }

    /// The next `n` records of `N` bytes stored as `N` byte planes (every record's
    /// first byte, then every second byte, …), each record put back together.
    pub(crate) fn planes<const N: usize>(
        &mut self,
        n: usize,
        what: &str,
    ) -> Result<Vec<[u8; N]>, String> {
        let mut out = vec![[0u8; N]; n];
        for k in 0..N {
            for (o, &v) in out.iter_mut().zip(self.take(n, what)?) {
                o[k] = v;
            }
        }
        Ok(out)
    }

    /// Bytes not read yet: none, once a body is read through.
    pub(crate) fn left(&self) -> usize {
        self.b.len() - self.at
    }
}

/// The body of a format whose length its content fixes (varints): the bytes between a
/// fixed header of `header_len` bytes and the crc32 in the last four, once there is room
/// for both and the checksum matches.
pub(crate) fn checked_body(b: &[u8], header_len: usize) -> Result<&[u8], String> {
    at_least(
        b.len(),
        (header_len + CRC_LEN) as u64,
        "the header alone takes",
    )?;
    checksum(b, b.len() - CRC_LEN)?;
    Ok(&b[header_len..b.len() - CRC_LEN])
}

/// Rewrites the crc32 in the last four bytes of `b` to that of the bytes before it:
/// damaged bytes that pass the checksum, to reach the content checks (nothing when
/// `b` is shorter than a crc32).
pub(crate) fn reseal(b: &mut [u8]) {
    let Some(at) = b.len().checked_sub(CRC_LEN) else {
        return;
    };
    let crc = crc32fast::hash(&b[..at]);
    b[at..].copy_from_slice(&crc.to_le_bytes());
}

/// Checks that `decode` refuses every truncation of `good` and `good` with any one byte
/// flipped, and names a byte slipped in before the checksum (resealed) as trailing: what
/// a format whose body is read through exactly must do.
#[cfg(test)]
pub(crate) fn refuses_every_damage<T, E: Display>(
    good: &[u8],
    decode: impl Fn(&[u8]) -> Result<T, E>,
) {
    for len in 0..good.len() {
        assert!(decode(&good[..len]).is_err(), "cut to {len} bytes");
    }
    for at in 0..good.len() {
        let mut b = good.to_vec();
        b[at] ^= 0x5a;
        assert!(decode(&b).is_err(), "byte {at} flipped");
    }
    let mut longer = good.to_vec();
    longer.insert(good.len() - CRC_LEN, 0);
    reseal(&mut longer);
    match decode(&longer) {
        Ok(_) => panic!("a byte slipped in passed"),
        Err(e) => assert!(e.to_string().contains("trailing"), "{e}"),
    }
}

/// Hands `decode` `rounds` mangled inputs, which it must survive without a panic: even
/// rounds random bytes (fewer than `max_len`), odd rounds `good` with one to five bytes
/// replaced. Rounds 1, 5, 9, … pass through `restore` first, which puts back what the
/// decoder checks first (magic, version, checksum) so that the damage reaches the
/// content checks.
#[cfg(test)]
pub(crate) fn mangled(
    seed: u64,
    rounds: usize,
    max_len: u32,
    good: &[u8],
    restore: impl Fn(&mut [u8]),
    mut decode: impl FnMut(&[u8]),
) {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    for round in 0..rounds {
        let mut b: Vec<u8> = if round % 2 == 0 {
            let len = rng.gen_range(0..max_len);
            (0..len).map(|_| rng.gen()).collect()
        } else {
            let mut b = good.to_vec();
            for _ in 0..rng.gen_range(1..6) {
                let at = rng.gen_range(0..b.len());
                b[at] = rng.gen();
            }
            b
        };
        if round % 4 == 1 {
            restore(&mut b);
        }
        decode(&b);
    }
}
