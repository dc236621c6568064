//! The checkpoint file `checkpoint.bin`: everything a run needs to continue where it was.
//!
//! Layout (all integers little-endian):
//!
//! | bytes | content |
//! | --- | --- |
//! | 21 | the magic line `stickslip checkpoint\n` |
//! | 4 | format version ([`VERSION`]) |
//! | 8 | length `H` of the header |
//! | `H` | header: MessagePack (the scene, the runner's state, the output positions) |
//! | rest | engine state: MessagePack, to the trailer |
//! | 16 | trailer: length of everything before it, and its [`Checksum`] |
//!
//! MessagePack (`rmp-serde`, structs written as maps with their field names) rather than
//! JSON: the engines' state holds infinite times (a channel at rate 0 never fires) that
//! JSON cannot represent (`serde_json` writes them as `null`); it keeps every `f64` bit for
//! bit in 9 bytes; and it is 3–4 times smaller and faster at large `N` (docs/runs.md).
//! Maps with field names, not positional arrays, because some state skips fields that are
//! `None` when serialized.
//!
//! The file is written as `checkpoint.bin.part`, synced, renamed over `checkpoint.bin`, and
//! the directory is synced: a checkpoint is whole or absent, never half-written.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use serde::Serialize;
use serde::de::DeserializeOwned;

use super::atomic::sync_dir;
use super::state_codec;

/// The checkpoint's file name in the output directory.
pub const FILE: &str = "checkpoint.bin";
/// Format version written, and the only one read.
pub const VERSION: u32 = 12;
const MAGIC: &[u8; 21] = b"stickslip checkpoint\n";
const TRAILER: usize = 16;
const PREAMBLE: usize = MAGIC.len() + 4 + 8;

/// Why a checkpoint cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("{path} is not a stickslip checkpoint")]
    NotACheckpoint { path: PathBuf },
    #[error("{path} has checkpoint format {found}; this stickslip reads format {VERSION}")]
    Version { path: PathBuf, found: u32 },
    #[error("{path} is damaged or cut short (its checksum does not match)")]
    Damaged { path: PathBuf },
    #[error("{path}: cannot decode the {what}: {message}")]
    Decode { path: PathBuf, what: &'static str, message: String },
    #[error("cannot read {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
}

/// A 64-bit checksum over 8-byte words: `h <- rotl((h ^ w) * K, 31)`, then the length and
/// a final mix. Each step is a bijection of `h` for a fixed word, so any change confined to
/// one word always changes the result; it is not cryptographic. Its definition is fixed
/// here (not `std`'s hasher, which may change between Rust versions).
#[derive(Clone, Debug)]
pub struct Checksum {
    h: u64,
    pending: [u8; 8],
    n_pending: usize,
    len: u64,
}

impl Default for Checksum {
    fn default() -> Self {
        Checksum { h: 0x243F_6A88_85A3_08D3, pending: [0; 8], n_pending: 0, len: 0 }
    }
}

impl Checksum {
    const K: u64 = 0x9E37_79B9_7F4A_7C15;
    #[inline]
    fn word(&mut self, w: u64) {
        self.h = (self.h ^ w).wrapping_mul(Self::K).rotate_left(31);
    }
    pub fn update(&mut self, mut bytes: &[u8]) {
        self.len += bytes.len() as u64;
        if self.n_pending > 0 {
            let take = (8 - self.n_pending).min(bytes.len());
            self.pending[self.n_pending..self.n_pending + take].copy_from_slice(&bytes[..take]);
            self.n_pending += take;
            bytes = &bytes[take..];
            if self.n_pending < 8 {
                return;
            }
            self.word(u64::from_le_bytes(self.pending));
            self.n_pending = 0;
        }
        let mut words = bytes.chunks_exact(8);
        for w in &mut words {
            self.word(u64::from_le_bytes(w.try_into().expect("8 bytes")));
        }
        let rest = words.remainder();
        self.pending[..rest.len()].copy_from_slice(rest);
        self.n_pending = rest.len();
    }
    pub fn finish(&self) -> u64 {
        let mut c = self.clone();
        if c.n_pending > 0 {
            c.pending[c.n_pending..].fill(0);
            c.word(u64::from_le_bytes(c.pending));
        }
        c.word(c.len);
        // SplitMix64's finaliser.
        let mut z = c.h;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// The checksum of `bytes`.
    pub fn of(bytes: &[u8]) -> u64 {
        let mut c = Checksum::default();
        c.update(bytes);
        c.finish()
    }
}

/// A writer that checksums what passes through it.
struct Summing<W: Write> {
    inner: W,
    sum: Checksum,
}

impl<W: Write> Write for Summing<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.sum.update(&buf[..n]);
        Ok(n)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

fn encode_error(e: rmp_serde::encode::Error) -> io::Error {
    io::Error::other(e)
}

/// Writes `header` and `engine` to `dir/checkpoint.bin` atomically (temporary file, sync,
/// rename, directory sync). Returns the size of the file in bytes.
pub fn write<H: Serialize, E: Serialize>(dir: &Path, header: &H, engine: &E) -> io::Result<u64> {
    let part = dir.join(format!("{FILE}.part"));
    let result = write_part(&part, header, engine);
    match result {
        Ok(len) => {
            std::fs::rename(&part, dir.join(FILE))?;
            sync_dir(dir)?;
            Ok(len)
        }
        Err(e) => {
            let _ = std::fs::remove_file(&part);
            Err(e)
        }
    }
}

fn write_part<H: Serialize, E: Serialize>(part: &Path, header: &H, engine: &E) -> io::Result<u64> {
    let mut head = Vec::new();
    header.serialize(&mut rmp_serde::Serializer::new(&mut head).with_struct_map()).map_err(encode_error)?;
    let file = File::create(part)?;
    let mut w = BufWriter::with_capacity(1 << 20, Summing { inner: file, sum: Checksum::default() });
    w.write_all(MAGIC)?;
    w.write_all(&VERSION.to_le_bytes())?;
    w.write_all(&(head.len() as u64).to_le_bytes())?;
    w.write_all(&head)?;
    state_codec::encode(&mut w, engine).map_err(encode_error)?;
    w.flush()?;
    let Summing { inner: mut file, sum } = w.into_inner().map_err(|e| e.into_error())?;
    let len = sum.len;
    file.write_all(&len.to_le_bytes())?;
    file.write_all(&sum.finish().to_le_bytes())?;
    file.sync_all()?;
    Ok(len + TRAILER as u64)
}

/// A checkpoint read into memory and verified; the engine state is decoded separately,
/// once the engine's type is known.
pub struct Loaded<H> {
    pub path: PathBuf,
    pub header: H,
    bytes: Vec<u8>,
    engine_at: usize,
}

impl<H> Loaded<H> {
    /// Size of the file in bytes.
    pub fn size(&self) -> u64 {
        self.bytes.len() as u64
    }
    /// Decodes the engine state as type `E`.
    pub fn engine<E: DeserializeOwned>(&self) -> Result<E, CheckpointError> {
        let body = &self.bytes[self.engine_at..self.bytes.len() - TRAILER];
        state_codec::decode(body).map_err(|e| self.decode("engine state", e))
    }
    fn decode(&self, what: &'static str, e: impl std::fmt::Display) -> CheckpointError {
        CheckpointError::Decode { path: self.path.clone(), what, message: e.to_string() }
    }
}

/// Reads and verifies `path` (magic, version, length, checksum) and decodes its header.
pub fn read<H: DeserializeOwned>(path: &Path) -> Result<Loaded<H>, CheckpointError> {
    // A checkpoint is a regular file (a link to a device such as /dev/zero would be read
    // without end).
    let meta = std::fs::metadata(path).map_err(|source| CheckpointError::Io { path: path.to_path_buf(), source })?;
    if !meta.is_file() {
        return Err(CheckpointError::NotACheckpoint { path: path.to_path_buf() });
    }
    let bytes = std::fs::read(path).map_err(|source| CheckpointError::Io { path: path.to_path_buf(), source })?;
    let path = path.to_path_buf();
    if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
        return Err(CheckpointError::NotACheckpoint { path });
    }
    if bytes.len() < PREAMBLE + TRAILER {
        return Err(CheckpointError::Damaged { path });
    }
    let u64_at = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"));
    let version = u32::from_le_bytes(bytes[MAGIC.len()..MAGIC.len() + 4].try_into().expect("4 bytes"));
    if version != VERSION {
        return Err(CheckpointError::Version { path, found: version });
    }
    let body_len = bytes.len() - TRAILER;
    if u64_at(body_len) != body_len as u64 || u64_at(body_len + 8) != Checksum::of(&bytes[..body_len]) {
        return Err(CheckpointError::Damaged { path });
    }
    let head_len = u64_at(MAGIC.len() + 4);
    if head_len > (body_len - PREAMBLE) as u64 {
        return Err(CheckpointError::Damaged { path });
    }
    let engine_at = PREAMBLE + head_len as usize;
    let header = rmp_serde::from_slice(&bytes[PREAMBLE..engine_at]).map_err(|e| CheckpointError::Decode {
        path: path.clone(),
        what: "header",
        message: e.to_string(),
    })?;
    Ok(Loaded { path, header, bytes, engine_at })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    struct Head {
        name: String,
        t: f64,
        #[serde(skip_serializing_if = "Option::is_none")]
        skipped: Option<u64>,
    }

    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    struct State {
        times: Vec<f64>,
        big: u128,
    }

    fn sample() -> (Head, State) {
        (
            Head { name: "x".into(), t: 1.5, skipped: None },
            State {
                times: vec![f64::INFINITY, -0.0, 0.1 + 0.2, f64::MIN_POSITIVE / 3.0, f64::NAN],
                big: u128::MAX - 7,
            },
        )
    }

    #[test]
    fn round_trip_keeps_every_bit() {
        let dir = tempfile::tempdir().unwrap();
        let (h, s) = sample();
        let len = write(dir.path(), &h, &s).unwrap();
        assert!(!dir.path().join("checkpoint.bin.part").exists());
        let l: Loaded<Head> = read(&dir.path().join(FILE)).unwrap();
        assert_eq!(l.size(), len);
        assert_eq!(l.header, h);
        let back: State = l.engine().unwrap();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&back.times), bits(&s.times));
        assert_eq!(back.big, s.big);
    }

    #[test]
    fn damage_is_detected() {
        let dir = tempfile::tempdir().unwrap();
        let (h, s) = sample();
        write(dir.path(), &h, &s).unwrap();
        let path = dir.path().join(FILE);
        let good = std::fs::read(&path).unwrap();
        // Any flipped byte, and any truncation, is refused.
        for at in (0..good.len()).step_by(7) {
            let mut bad = good.clone();
            bad[at] ^= 0x10;
            std::fs::write(&path, &bad).unwrap();
            let r = read::<Head>(&path);
            assert!(
                matches!(
                    r,
                    Err(CheckpointError::Damaged { .. }
                        | CheckpointError::NotACheckpoint { .. }
                        | CheckpointError::Version { .. })
                ),
                "flip at {at}"
            );
        }
        for len in [0, 5, 30, good.len() / 2, good.len() - 1] {
            std::fs::write(&path, &good[..len]).unwrap();
            assert!(read::<Head>(&path).is_err(), "cut to {len}");
        }
        std::fs::write(&path, b"{\"json\": true}").unwrap();
        assert!(matches!(read::<Head>(&path), Err(CheckpointError::NotACheckpoint { .. })));
        // Not a regular file: a directory, and a device read without end.
        assert!(matches!(read::<Head>(dir.path()), Err(CheckpointError::NotACheckpoint { .. })));
        assert!(matches!(read::<Head>(Path::new("/dev/zero")), Err(CheckpointError::NotACheckpoint { .. })));
    }

    #[test]
    fn checksum_is_independent_of_how_bytes_arrive() {
        let data: Vec<u8> = (0..1000u32).map(|i| (i * 37 % 251) as u8).collect();
        let whole = Checksum::of(&data);
        let mut c = Checksum::default();
        for chunk in data.chunks(13) {
            c.update(chunk);
        }
        assert_eq!(c.finish(), whole);
        assert_ne!(Checksum::of(&data[..999]), whole);
        let mut zeros = data.clone();
        zeros.push(0);
        assert_ne!(Checksum::of(&zeros), whole, "trailing zero bytes change the sum (length is mixed in)");
    }
}
