//! The fragment dump: a little-endian binary file of one frame's fragment stream, for
//! evaluating fragments captured from another renderer (`oit-lab evaluate` reads one,
//! `oit-lab dump` writes a scene's: [`crate::study::dump`]). The format stays here, beside
//! [`crate::stream`]: a lower floor that the commands use, and the file `oit-lab evaluate
//! --help` cites.
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 8 | magic `OITFRAG2` (ASCII) |
//! | 8 | 4 | width, u32, 1 ..= 16384 |
//! | 12 | 4 | height, u32, 1 ..= 16384 |
//! | 16 | 12 | background linear RGB, 3 x f32, finite, >= 0 |
//! | 28 | 8 | fragment count `n`, u64 |
//! | 36 | 32 n | fragments in submission order |
//!
//! Each fragment (32 bytes): x u32, y u32, depth f32 (distance from the viewer, smaller is
//! nearer, finite), premultiplied color 3 x f32 (each in `[0, 1]`), alpha f32 (`[0, 1]`), key
//! u32: the id of the primitive that emitted it ([`Frag::prim`], the kernel's fragment key:
//! unique per primitive within a pixel's fragments, the same in every frame), so that
//! `evaluate` replays the bytes of a renderer that keys its fragments. The file ends right
//! after the last fragment. Every value is checked on reading: a bad file gives a
//! [`DumpError`] naming what and where, never a panic.
//!
//! The first version of the format, magic `OITFRAG1`, has 28-byte fragments without the key;
//! it is still read, each fragment keyed by its index in the file (unique in the frame).
use crate::stream::{Frag, Stream};
use mlab::FragmentError;

/// The magic bytes (what [`to_bytes`] writes).
pub const MAGIC: [u8; 8] = *b"OITFRAG2";
/// The magic bytes of the first version, without keys (still read).
pub const MAGIC_V1: [u8; 8] = *b"OITFRAG1";
/// Header size in bytes.
pub const HEADER: usize = 36;
/// Fragment record size in bytes.
pub const RECORD: usize = 32;
/// Fragment record size of the first version, without the key.
pub const RECORD_V1: usize = 28;
/// Largest width or height.
pub const MAX_SIDE: u32 = 16384;

/// Why a dump was refused.
#[derive(Debug, PartialEq)]
pub enum DumpError {
    /// The file could not be read or written.
    Io(String),
    /// The first 8 bytes are neither `OITFRAG2` nor `OITFRAG1`.
    BadMagic,
    /// Shorter than its header or than `36 + 32 n` bytes (`36 + 28 n` for `OITFRAG1`).
    Truncated {
        /// Bytes needed.
        expected: u64,
        /// Bytes present.
        actual: u64,
    },
    /// Bytes after the last fragment.
    TrailingBytes {
        /// Bytes expected.
        expected: u64,
        /// Bytes present.
        actual: u64,
    },
    /// Width or height is 0 or above 16384.
    BadSize(u32, u32),
    /// The background is not finite or negative.
    BadBackground,
    /// A fragment lies outside the frame.
    PixelOutOfRange {
        /// Fragment index.
        index: u64,
        /// x.
        x: u32,
        /// y.
        y: u32,
    },
    /// A fragment the kernel refuses (NaN, infinite, out of range).
    BadFragment {
        /// Fragment index.
        index: u64,
        /// Why.
        error: FragmentError,
    },
}

impl std::fmt::Display for DumpError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DumpError::Io(e) => write!(f, "{e}"),
            DumpError::BadMagic => write!(
                f,
                "not a fragment dump: the file does not start with OITFRAG2 or OITFRAG1"
            ),
            DumpError::Truncated { expected, actual } => {
                write!(f, "truncated fragment dump: {actual} bytes, the header says {expected}")
            }
            DumpError::TrailingBytes { expected, actual } => {
                write!(f, "fragment dump has {actual} bytes, the header says {expected}")
            }
            DumpError::BadSize(w, h) => write!(f, "frame size {w}x{h} is not within 1..={MAX_SIDE}"),
            DumpError::BadBackground => write!(f, "background color is not finite and non-negative"),
            DumpError::PixelOutOfRange { index, x, y } => {
                write!(f, "fragment {index}: pixel ({x}, {y}) is outside the frame")
            }
            DumpError::BadFragment { index, error } => write!(f, "fragment {index}: {error}"),
        }
    }
}

impl std::error::Error for DumpError {}

/// The dump of a stream.
pub fn to_bytes(s: &Stream) -> Vec<u8> {
    let mut b = Vec::with_capacity(HEADER + RECORD * s.frags.len());
    b.extend_from_slice(&MAGIC);
    b.extend_from_slice(&s.width.to_le_bytes());
    b.extend_from_slice(&s.height.to_le_bytes());
    for c in s.background {
        b.extend_from_slice(&c.to_le_bytes());
    }
    b.extend_from_slice(&(s.frags.len() as u64).to_le_bytes());
    for f in &s.frags {
        b.extend_from_slice(&(f.pixel % s.width).to_le_bytes());
        b.extend_from_slice(&(f.pixel / s.width).to_le_bytes());
        b.extend_from_slice(&f.depth.to_le_bytes());
        for c in f.color {
            b.extend_from_slice(&c.to_le_bytes());
        }
        b.extend_from_slice(&f.alpha.to_le_bytes());
        b.extend_from_slice(&f.prim.to_le_bytes());
    }
    b
}

fn u32_at(b: &[u8], o: usize) -> u32 {
    u32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]])
}

fn f32_at(b: &[u8], o: usize) -> f32 {
    f32::from_bits(u32_at(b, o))
}

/// Parse and check a dump, either version.
pub fn from_bytes(b: &[u8]) -> Result<Stream, DumpError> {
    let record = match b.get(..MAGIC.len()) {
        Some(m) if m == MAGIC => RECORD,
        Some(m) if m == MAGIC_V1 => RECORD_V1,
        _ => return Err(DumpError::BadMagic),
    };
    if b.len() < HEADER {
        return Err(DumpError::Truncated {
            expected: HEADER as u64,
            actual: b.len() as u64,
        });
    }
    let (width, height) = (u32_at(b, 8), u32_at(b, 12));
    if !(1..=MAX_SIDE).contains(&width) || !(1..=MAX_SIDE).contains(&height) {
        return Err(DumpError::BadSize(width, height));
    }
    let background = [f32_at(b, 16), f32_at(b, 20), f32_at(b, 24)];
    if background.iter().any(|c| !c.is_finite() || *c < 0.0) {
        return Err(DumpError::BadBackground);
    }
    let n = u64::from_le_bytes(b[28..36].try_into().unwrap_or([0; 8]));
    let expected = n
        .checked_mul(record as u64)
        .and_then(|x| x.checked_add(HEADER as u64))
        .unwrap_or(u64::MAX);
    let actual = b.len() as u64;
    if actual < expected {
        return Err(DumpError::Truncated { expected, actual });
    }
    if actual > expected {
        return Err(DumpError::TrailingBytes { expected, actual });
    }
    let mut frags = Vec::with_capacity(n as usize);
    for (i, r) in b[HEADER..].chunks_exact(record).enumerate() {
        let index = i as u64;
        let (x, y) = (u32_at(r, 0), u32_at(r, 4));
        if x >= width || y >= height {
            return Err(DumpError::PixelOutOfRange { index, x, y });
        }
        let f = Frag {
            pixel: y * width + x,
            depth: f32_at(r, 8),
            color: [f32_at(r, 12), f32_at(r, 16), f32_at(r, 20)],
            alpha: f32_at(r, 24),
            // The first version has no keys: each fragment is its own primitive.
            prim: if record == RECORD { u32_at(r, 28) } else { i as u32 },
        };
        f.to_kernel().map_err(|error| DumpError::BadFragment { index, error })?;
        frags.push(f);
    }
    Ok(Stream {
        width,
        height,
        background,
        frags,
    })
}

/// Read and check a dump file.
pub fn read(path: &std::path::Path) -> Result<Stream, DumpError> {
    let b = std::fs::read(path).map_err(|e| DumpError::Io(format!("{}: {e}", path.display())))?;
    from_bytes(&b)
}

/// Write a dump file.
pub fn write(path: &std::path::Path, s: &Stream) -> Result<(), DumpError> {
    std::fs::write(path, to_bytes(s)).map_err(|e| DumpError::Io(format!("{}: {e}", path.display())))
}
