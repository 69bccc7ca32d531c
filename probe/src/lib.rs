//! no_std probe: exercises the kernel from a `#![no_std]` staticlib with its own panic
//! handler, so a std leak anywhere in the dependency graph fails the build.
#![no_std]

use mlab::glam::Vec3;
use mlab::{Background, BlendingArray, Fragment, Framebuffer, Hybrid, MlabFramebuffer, Row};

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {}
}

/// Composite two fragments with MLAB and HT and write an RGBA8 pixel through a framebuffer.
#[unsafe(no_mangle)]
pub extern "C" fn mlab_probe(out: &mut [u8; 4]) -> i32 {
    let (Ok(a), Ok(b)) = (
        Fragment::straight(Vec3::X, 0.5, 1.0),
        Fragment::straight(Vec3::Y, 0.5, 2.0),
    ) else {
        return -1;
    };
    let mut m = BlendingArray::<2>::new();
    let mut h = Hybrid::<1>::new();
    for f in [&b, &a] {
        m.insert(f);
        h.insert(f);
    }
    let mut storage = [Row::EMPTY; 4];
    let Ok(mut fb) = MlabFramebuffer::<4>::new(&mut storage, 1, 1) else {
        return -2;
    };
    if fb.insert(0, 0, &a).is_err() {
        return -3;
    }
    let mut px = [[0u8; 4]; 1];
    if fb.resolve_rgba8(&mut px, Background::Opaque(Vec3::ZERO)).is_err() {
        return -4;
    }
    *out = px[0];
    (m.resolve().transmittance * 255.0) as i32 + (h.resolve().transmittance * 255.0) as i32
}
