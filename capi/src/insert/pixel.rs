//! The per-pixel inserts: one fragment, given as scalars, into one pixel, straight or
//! premultiplied color, without or with a stable key. One generic body (`insert_typed`,
//! reached through `insert_one`) serves the four exported functions: the key is a type
//! parameter, `()` for the unkeyed ones (nothing is passed) and `u32` for the keyed ones.

use mlab::framebuffer::{Ht, Mlab, Pixel};
use mlab::{Framebuffer, Grid, Paper, Spans, Unbiased};

use crate::fragment::{KeyArg, fragment};
use crate::framebuffer::{MlabFramebuffer, state};
use crate::status::MlabStatus;

/// One fragment into the pixel of a typed grid: straight or premultiplied color (`S`),
/// validated, given its key if it has one (`K`), then inserted.
///
/// The per-pixel inserts are the one place where the cost of the boundary is paid per
/// fragment, so they are written for it (MLAB 4, callgrind, against 233 instructions per
/// fragment for the Rust loop over `DynFramebuffer::insert`): the exported function checks
/// the state and calls the typed insert of its kind through a table (`insert_one`), with
/// the color as scalars in registers all the way, 277 instructions. Through `guard` and
/// `with_grid!` (a closure called by `catch_unwind`, the fragment validated outside it and
/// read back through memory, and 32 inlined inserts in one function) it ran 313; the same
/// with the table but still inside `guard`, 307. The keyed inserts have tables of their own
/// (`InsertTyped<u32>`), so that the unkeyed ones pass no key: their `K` is `()`, an argument
/// of no size, which the Rust calling convention does not pass.
#[allow(clippy::too_many_arguments)]
fn insert_typed<P: Pixel, const S: bool, K: KeyArg>(
    s: &MlabFramebuffer,
    x: u32,
    y: u32,
    r: f32,
    g: f32,
    b: f32,
    a: f32,
    depth: f32,
    key: K,
) -> MlabStatus {
    // The pixel, then the fragment (`docs/c.md`, "The order of the checks").
    if x >= s.width || y >= s.height {
        return MlabStatus::OutOfBounds;
    }
    let fragment = match fragment([r, g, b, a], depth, key.key(), S) {
        Ok(f) => f,
        Err(e) => return e.into(),
    };
    // SAFETY: `s` was checked by `state` (in `insert_one`); the caller's guarantee on its rows.
    let rows = unsafe { s.rows() };
    let r = Grid::<P, Spans>::new(rows, s.width, s.height)
        .and_then(|g| g.with_first_pixel(s.first).insert(x, y, &fragment));
    match r {
        Ok(()) => MlabStatus::Ok,
        Err(e) => e.into(),
    }
}

/// A typed per-pixel insert (`insert_typed`), its key `K` (`()`: none).
type InsertTyped<K> = fn(&MlabFramebuffer, u32, u32, f32, f32, f32, f32, f32, K) -> MlabStatus;

/// The 32 typed inserts of one color form (`$s`: straight) and key type (`$k`), by kind.
macro_rules! insert_table {
    ($s:literal, $k:ty) => {
        [
            insert_typed::<Mlab<1, Unbiased>, $s, $k>,
            insert_typed::<Mlab<2, Unbiased>, $s, $k>,
            insert_typed::<Mlab<3, Unbiased>, $s, $k>,
            insert_typed::<Mlab<4, Unbiased>, $s, $k>,
            insert_typed::<Mlab<5, Unbiased>, $s, $k>,
            insert_typed::<Mlab<6, Unbiased>, $s, $k>,
            insert_typed::<Mlab<7, Unbiased>, $s, $k>,
            insert_typed::<Mlab<8, Unbiased>, $s, $k>,
            insert_typed::<Ht<1, Unbiased>, $s, $k>,
            insert_typed::<Ht<2, Unbiased>, $s, $k>,
            insert_typed::<Ht<3, Unbiased>, $s, $k>,
            insert_typed::<Ht<4, Unbiased>, $s, $k>,
            insert_typed::<Ht<5, Unbiased>, $s, $k>,
            insert_typed::<Ht<6, Unbiased>, $s, $k>,
            insert_typed::<Ht<7, Unbiased>, $s, $k>,
            insert_typed::<Ht<8, Unbiased>, $s, $k>,
            insert_typed::<Mlab<1, Paper>, $s, $k>,
            insert_typed::<Mlab<2, Paper>, $s, $k>,
            insert_typed::<Mlab<3, Paper>, $s, $k>,
            insert_typed::<Mlab<4, Paper>, $s, $k>,
            insert_typed::<Mlab<5, Paper>, $s, $k>,
            insert_typed::<Mlab<6, Paper>, $s, $k>,
            insert_typed::<Mlab<7, Paper>, $s, $k>,
            insert_typed::<Mlab<8, Paper>, $s, $k>,
            insert_typed::<Ht<1, Paper>, $s, $k>,
            insert_typed::<Ht<2, Paper>, $s, $k>,
            insert_typed::<Ht<3, Paper>, $s, $k>,
            insert_typed::<Ht<4, Paper>, $s, $k>,
            insert_typed::<Ht<5, Paper>, $s, $k>,
            insert_typed::<Ht<6, Paper>, $s, $k>,
            insert_typed::<Ht<7, Paper>, $s, $k>,
            insert_typed::<Ht<8, Paper>, $s, $k>,
        ]
    };
}

/// The per-pixel inserts by kind (the index `with_grid!` matches on), straight color.
static INSERT_STRAIGHT: [InsertTyped<()>; 32] = insert_table!(true, ());
/// The per-pixel inserts by kind, premultiplied color.
static INSERT_PREMULTIPLIED: [InsertTyped<()>; 32] = insert_table!(false, ());
/// The keyed per-pixel inserts by kind, straight color.
static INSERT_STRAIGHT_KEYED: [InsertTyped<u32>; 32] = insert_table!(true, u32);
/// The keyed per-pixel inserts by kind, premultiplied color.
static INSERT_PREMULTIPLIED_KEYED: [InsertTyped<u32>; 32] = insert_table!(false, u32);

/// A per-pixel insert, keyed or not (`K`): the state checked, then a tail call of the typed
/// insert of its kind.
///
/// Not under `guard` (no `catch_unwind`), for its cost per fragment: a panic here would
/// abort the process (Rust's rule for a panic that reaches an `extern "C"` function), so this
/// is right only while the kernel cannot panic, on any input (`docs/reliability.md`: it
/// returns errors, and is fuzzed for it). A kernel change that can panic must put these
/// inserts under `guard`.
///
/// # Safety
/// As `mlab_insert_straight`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
unsafe fn insert_one<K: KeyArg>(
    table: &[InsertTyped<K>; 32],
    fb: *mut MlabFramebuffer,
    x: u32,
    y: u32,
    r: f32,
    g: f32,
    b: f32,
    a: f32,
    depth: f32,
    key: K,
) -> MlabStatus {
    // SAFETY: the caller's guarantee on `fb`.
    let s = match unsafe { state(fb) } {
        Ok(s) => s,
        Err(e) => return e,
    };
    match table.get(s.kind() as usize) {
        Some(insert) => insert(s, x, y, r, g, b, a, depth, key),
        None => MlabStatus::NotInitialized,
    }
}

/// Inserts one fragment of **straight** (not premultiplied) linear color `r, g, b`, alpha `a`
/// and depth (smaller is nearer) into pixel `(x, y)`: Listing 1 (MLAB) or 2 (HT) of the
/// paper, quantized by the framebuffer's arithmetic. Refused, nothing changed: a pixel
/// outside (checked first), then an invalid fragment (NaN, infinite, negative color, alpha
/// outside `[0, 1]`, `color * alpha` above 1, infinite depth: the first failing check in
/// the order of `docs/c.md`). Without a key: the dithers of the default arithmetic are seeded by
/// the fragment's content, and re-roll when its depth changes (`mlab_insert_straight_keyed`).
///
/// # Safety
/// `fb` is null or points to a readable `MlabFramebuffer` whose storage satisfies the
/// guarantees of `mlab_framebuffer_init`.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn mlab_insert_straight(
    fb: *mut MlabFramebuffer,
    x: u32,
    y: u32,
    r: f32,
    g: f32,
    b: f32,
    a: f32,
    depth: f32,
) -> MlabStatus {
    // SAFETY: the caller's guarantee, passed on.
    unsafe { insert_one(&INSERT_STRAIGHT, fb, x, y, r, g, b, a, depth, ()) }
}

/// `mlab_insert_straight` with **premultiplied** color (`r, g, b` already multiplied by
/// alpha; each at most 1, may exceed alpha: additive light).
///
/// # Safety
/// As `mlab_insert_straight`.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn mlab_insert_premultiplied(
    fb: *mut MlabFramebuffer,
    x: u32,
    y: u32,
    r: f32,
    g: f32,
    b: f32,
    a: f32,
    depth: f32,
) -> MlabStatus {
    // SAFETY: the caller's guarantee, passed on.
    unsafe { insert_one(&INSERT_PREMULTIPLIED, fb, x, y, r, g, b, a, depth, ()) }
}

/// `mlab_insert_straight` with a **stable key**: the id of what emitted the fragment, unique
/// in the frame and the same in every frame (the primitive's id: a triangle's index in a
/// software rasterizer; in a shader `gl_PrimitiveID` or `SV_PrimitiveID` mixed with the draw
/// or instance id). The default arithmetic seeds its dithers with the key and the pixel, so
/// a fragment is rounded the same way in every frame while the camera moves; without a key
/// (`mlab_insert_straight`) the seed is the fragment's content, which changes with its depth,
/// and a dense faint layer shimmers under camera motion. The paper arithmetic ignores the
/// key. The bytes of the Rust API's `Fragment::with_key(key)`; the same checks and statuses
/// as `mlab_insert_straight`.
///
/// # Safety
/// As `mlab_insert_straight`.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn mlab_insert_straight_keyed(
    fb: *mut MlabFramebuffer,
    x: u32,
    y: u32,
    r: f32,
    g: f32,
    b: f32,
    a: f32,
    depth: f32,
    key: u32,
) -> MlabStatus {
    // SAFETY: the caller's guarantee, passed on.
    unsafe { insert_one(&INSERT_STRAIGHT_KEYED, fb, x, y, r, g, b, a, depth, key) }
}

/// `mlab_insert_premultiplied` with a stable key (`mlab_insert_straight_keyed`).
///
/// # Safety
/// As `mlab_insert_straight`.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn mlab_insert_premultiplied_keyed(
    fb: *mut MlabFramebuffer,
    x: u32,
    y: u32,
    r: f32,
    g: f32,
    b: f32,
    a: f32,
    depth: f32,
    key: u32,
) -> MlabStatus {
    // SAFETY: the caller's guarantee, passed on.
    unsafe { insert_one(&INSERT_PREMULTIPLIED_KEYED, fb, x, y, r, g, b, a, depth, key) }
}
