//! The defect model of fragment validation, written independently of the kernel's code
//! from the raw constructor arguments the fuzz input decodes ([`RawFragment`]). The
//! reference models of the arithmetics, the exact oracle and the lanes checks are the
//! shared `mlab-reference` crate (`reference/`).

use mlab::FragmentError;

use crate::input::{Ctor, RawFragment};

/// A set of [`FragmentError`]s (one bit per variant).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Defects(u16);

/// The bit of an error variant. `FragmentError` is `#[non_exhaustive]`: a new variant
/// fails here until the model learns it.
pub fn defect_bit(e: FragmentError) -> u16 {
    1 << match e {
        FragmentError::NanColor => 0,
        FragmentError::InfiniteColor => 1,
        FragmentError::NegativeColor => 2,
        FragmentError::ColorAboveOne => 3,
        FragmentError::NanAlpha => 4,
        FragmentError::AlphaOutOfRange => 5,
        FragmentError::NanDepth => 6,
        FragmentError::InfiniteDepth => 7,
        other => panic!("the defect model does not know {other:?}"),
    }
}

impl Defects {
    fn add(&mut self, e: FragmentError, present: bool) {
        if present {
            self.0 |= defect_bit(e);
        }
    }

    /// No defect.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// `e` is one of the defects.
    pub fn contains(self, e: FragmentError) -> bool {
        self.0 & defect_bit(e) != 0
    }
}

/// What a valid fragment must hold: premultiplied color and alpha, as f32, bit for bit.
#[derive(Clone, Copy, Debug)]
pub struct Expected {
    /// Premultiplied color.
    pub color: [f32; 3],
    /// Alpha.
    pub alpha: f32,
}

/// Every defect of the raw arguments (the kernel must return one of them, or `Ok` when
/// there is none), and the fields a valid fragment must hold.
pub fn defects(f: &RawFragment) -> (Defects, Expected) {
    let mut d = Defects::default();
    let a_in = f.a;
    d.add(FragmentError::NanAlpha, a_in.is_nan());
    d.add(
        FragmentError::AlphaOutOfRange,
        !a_in.is_nan() && !(0.0..=1.0).contains(&a_in),
    );
    let alpha = if f.ctor == Ctor::WithTransmittance {
        1.0 - a_in
    } else {
        a_in
    };
    d.add(FragmentError::NanColor, f.color.iter().any(|c| c.is_nan()));
    d.add(FragmentError::InfiniteColor, f.color.iter().any(|c| c.is_infinite()));
    d.add(FragmentError::NegativeColor, f.color.iter().any(|&c| c < 0.0));
    d.add(FragmentError::NanDepth, f.z.is_nan());
    d.add(FragmentError::InfiniteDepth, f.z.is_infinite());
    let color = if f.ctor == Ctor::Straight {
        f.color.map(|c| c * alpha)
    } else {
        f.color
    };
    d.add(FragmentError::ColorAboveOne, color.iter().any(|&c| c > 1.0));
    (d, Expected { color, alpha })
}
