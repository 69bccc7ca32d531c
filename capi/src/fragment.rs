//! The fragments of the span and batch inserts as C structs, without and with a stable key
//! (separate structs on purpose: no struct grows), read by the inserts through one trait
//! each, and the validation of one fragment (`fragment`).

use mlab::lanes::FragmentLanes;
use mlab::{Fragment, FragmentError};

/// Eight fragments of one line of 8 pixels, structure of arrays (lane `i` is pixel
/// `(x + i, y)`), for the span inserts, without keys (their dithers are seeded by their
/// content: `docs/c.md`, "Stable fragment keys"). With keys: `MlabFragmentSpanKeyed`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MlabFragmentSpan {
    /// Red per lane (straight or premultiplied, as the function says; linear).
    pub r: [f32; 8],
    /// Green per lane.
    pub g: [f32; 8],
    /// Blue per lane.
    pub b: [f32; 8],
    /// Alpha per lane.
    pub a: [f32; 8],
    /// Depth per lane (smaller is nearer).
    pub depth: [f32; 8],
}

/// `MlabFragmentSpan` with a stable key per lane, for the keyed span inserts
/// (`mlab_insert_span_straight_keyed`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MlabFragmentSpanKeyed {
    /// Red per lane (straight or premultiplied, as the function says; linear).
    pub r: [f32; 8],
    /// Green per lane.
    pub g: [f32; 8],
    /// Blue per lane.
    pub b: [f32; 8],
    /// Alpha per lane.
    pub a: [f32; 8],
    /// Depth per lane (smaller is nearer).
    pub depth: [f32; 8],
    /// The stable key per lane: the id of the primitive that emitted the lane's fragment,
    /// unique in the frame and the same in every frame (`mlab_insert_straight_keyed`).
    pub key: [u32; 8],
}

/// One fragment of a batch: its pixel, its straight or premultiplied RGBA (linear) and depth,
/// without a key (its dithers are seeded by its content). With a key:
/// `MlabPixelFragmentKeyed`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MlabPixelFragment {
    /// Column.
    pub x: u32,
    /// Line.
    pub y: u32,
    /// R, G, B, A (straight or premultiplied, as the function says).
    pub rgba: [f32; 4],
    /// Depth (smaller is nearer).
    pub depth: f32,
}

/// `MlabPixelFragment` with a stable key (32 bytes), for the keyed batch inserts
/// (`mlab_insert_batch_straight_keyed`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MlabPixelFragmentKeyed {
    /// Column.
    pub x: u32,
    /// Line.
    pub y: u32,
    /// R, G, B, A (straight or premultiplied, as the function says).
    pub rgba: [f32; 4],
    /// Depth (smaller is nearer).
    pub depth: f32,
    /// The stable key: the id of the primitive that emitted the fragment, unique in the
    /// frame and the same in every frame (`mlab_insert_straight_keyed`).
    pub key: u32,
}

/// The fragments of a span insert, with or without keys.
pub(crate) trait SpanFragments: Copy {
    /// The kernel's lanes of the 8 fragments, with their keys if they have them.
    fn lanes(self) -> FragmentLanes;
}

/// A fragment of a batch, with or without a key.
pub(crate) trait PixelFragment: Copy {
    /// Its pixel, RGBA, depth and key.
    fn parts(&self) -> (u32, u32, [f32; 4], f32, Option<u32>);
}

/// Both traits for one pair of C structs (span, batch fragment), the key read by `$key` (of
/// the struct `$f`): one definition for the unkeyed and the keyed pair, which differ only
/// there.
macro_rules! fragment_traits {
    ($span:ty, $pixel:ty, |$f:ident| $key:expr) => {
        impl SpanFragments for $span {
            #[inline(always)]
            fn lanes(self) -> FragmentLanes {
                let $f = self;
                FragmentLanes {
                    color: [$f.r, $f.g, $f.b],
                    alpha: $f.a,
                    depth: $f.depth,
                    key: $key,
                }
            }
        }

        impl PixelFragment for $pixel {
            #[inline(always)]
            fn parts(&self) -> (u32, u32, [f32; 4], f32, Option<u32>) {
                let $f = self;
                ($f.x, $f.y, $f.rgba, $f.depth, $key)
            }
        }
    };
}

fragment_traits!(MlabFragmentSpan, MlabPixelFragment, |_f| None);
fragment_traits!(MlabFragmentSpanKeyed, MlabPixelFragmentKeyed, |f| Some(f.key));

/// The key argument of a per-pixel insert: `()` for the unkeyed functions (no size: nothing
/// is passed), `u32` for the keyed ones.
pub(crate) trait KeyArg: Copy {
    /// The fragment's key, if it has one.
    fn key(self) -> Option<u32>;
}

impl KeyArg for () {
    #[inline(always)]
    fn key(self) -> Option<u32> {
        None
    }
}

impl KeyArg for u32 {
    #[inline(always)]
    fn key(self) -> Option<u32> {
        Some(self)
    }
}

/// A validated fragment, straight color or not, with its key if it has one.
#[inline(always)]
pub(crate) fn fragment(
    rgba: [f32; 4],
    depth: f32,
    key: Option<u32>,
    straight: bool,
) -> Result<Fragment, FragmentError> {
    let f = if straight {
        Fragment::straight_rgba(rgba, depth)
    } else {
        Fragment::premultiplied_rgba(rgba, depth)
    }?;
    Ok(match key {
        Some(k) => f.with_key(k),
        None => f,
    })
}
