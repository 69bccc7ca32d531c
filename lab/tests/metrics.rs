//! The issue 10 metrics against hand-computed cases: SSIM, FLIP over covered pixels, the
//! change between two orders, and the combined scores.

use oit_lab::methods::Image;
use oit_lab::metrics::{CHANGE_LEVELS, FlipMap, change, mean_where, score, ssim_map};

fn image(w: u32, h: u32, f: impl Fn(usize) -> [f32; 3]) -> Image {
    let n = (w * h) as usize;
    Image {
        width: w,
        height: h,
        rgb: (0..n).map(f).collect(),
        vis: vec![1.0; n],
    }
}

#[test]
fn mean_where_by_hand() {
    // (1 + 4) / 2 over the two selected entries; nothing selected gives 0.
    assert_eq!(mean_where(&[1.0f32, 2.0, 4.0], &[true, false, true]), 2.5);
    assert_eq!(mean_where(&[1.0f64, 2.0], &[false, false]), 0.0);
}

#[test]
fn ssim_identical_is_one() {
    let a = image(13, 7, |p| [(p % 5) as f32 / 5.0, 0.3, (p % 3) as f32 / 3.0]);
    for s in ssim_map(&a, &a) {
        assert!((s - 1.0).abs() < 1e-12, "{s}");
    }
}

#[test]
fn ssim_constant_images_by_hand() {
    // Constant images: every window has sigma_x = sigma_y = sigma_xy = 0, so the contrast and
    // structure term is C2 / C2 = 1 and SSIM = (2 mu_x mu_y + C1) / (mu_x^2 + mu_y^2 + C1),
    // C1 = (0.01 * 1)^2 = 1e-4. Linear 1 and 0 encode to sRGB 1 and 0 exactly.
    // White against black: (0 + 1e-4) / (1 + 0 + 1e-4) = 9.999e-5 per channel.
    let white = image(20, 20, |_| [1.0; 3]);
    let black = image(20, 20, |_| [0.0; 3]);
    for s in ssim_map(&white, &black) {
        assert!((s - 1e-4 / (1.0 + 1e-4)).abs() < 1e-9, "{s}");
    }
    // Only blue differs: channels R, G give 1, B gives 9.999e-5; mean (2 + 9.999e-5) / 3.
    let yellow = image(20, 20, |_| [1.0, 1.0, 0.0]);
    for s in ssim_map(&white, &yellow) {
        assert!((s - (2.0 + 1e-4 / (1.0 + 1e-4)) / 3.0).abs() < 1e-9, "{s}");
    }
}

#[test]
fn ssim_two_pixels_swapped_by_hand() {
    // A 2x1 image, x = [0, 1] against y = [1, 0] (all channels). At pixel 0 the window cut to
    // the image holds pixel 0 with weight 1 and pixel 1 with weight e^(-1/(2 * 1.5^2)) =
    // e^(-0.2222) = 0.800737, renormalized: p = 1 / 1.800737 = 0.555328, q = 0.444672.
    // mu_x = q = 0.444672, mu_y = p = 0.555328, sigma_x^2 = sigma_y^2 = p q = 0.246939,
    // sigma_xy = (0 - q)(1 - p) p + (1 - q)(0 - p) q = -p q = -0.246939.
    // SSIM = (2 * 0.246939 + 1e-4)(-2 * 0.246939 + 9e-4)
    //      / ((0.197733 + 0.308389 + 1e-4)(2 * 0.246939 + 9e-4))
    //      = (0.493978 * -0.492978) / (0.506222 * 0.494778) = -0.972261.
    // Pixel 1 is the mirror image: the same value.
    let x = image(2, 1, |p| [p as f32; 3]);
    let y = image(2, 1, |p| [1.0 - p as f32; 3]);
    for s in ssim_map(&x, &y) {
        assert!((s + 0.972261).abs() < 1e-5, "{s}");
    }
}

#[test]
fn flip_over_covered_pixels_by_hand() {
    // 96x16: the test differs from the reference only in columns 64..96. FLIP's filters reach
    // a few pixels at 67 pixels per degree, so columns 0..16 (48 away) have error exactly 0:
    // over them the mean is 0, while the whole image's is not.
    let reference = image(96, 16, |_| [0.25; 3]);
    let test = image(96, 16, |p| if p % 96 >= 64 { [0.9, 0.1, 0.1] } else { [0.25; 3] });
    let map = FlipMap::new(&reference, &test);
    let left: Vec<bool> = (0..96 * 16).map(|p| p % 96 < 16).collect();
    assert_eq!(map.mean_where(&left), 0.0);
    assert!(map.mean() > 0.05, "{}", map.mean());
    // The right third alone has a larger mean than the whole image (a third of its pixels).
    let right: Vec<bool> = (0..96 * 16).map(|p| p % 96 >= 64).collect();
    assert!(map.mean_where(&right) > 2.5 * map.mean());
    // Identical images: 0 everywhere, and one color of nv-flip's magma map everywhere.
    let zero = FlipMap::new(&reference, &reference);
    assert!(zero.values.iter().all(|&v| v == 0.0));
    let rgb = zero.magma();
    assert_eq!(rgb.len(), 96 * 16 * 3);
    assert!(rgb.chunks(3).all(|c| c == rgb[..3].to_vec().as_slice()));
}

#[test]
fn change_between_orders_by_hand() {
    // 4 pixels, pixel 3 not covered. sRGB8 of linear 0.5 is 188 (0.735357 * 255 = 187.52),
    // of 0.51 it is 189 (0.741905 * 255 = 189.19: 1 level), of 0.53 it is 192 (0.754781 * 255
    // = 192.47: 4 levels); linear 0 and 1 are 0 and 255.
    let a = image(4, 1, |p| [[0.5; 3], [0.5; 3], [0.0; 3], [0.0; 3]][p]);
    let b = image(4, 1, |p| [[0.51, 0.5, 0.5], [0.5, 0.5, 0.53], [0.0; 3], [1.0; 3]][p]);
    let covered = [true, true, true, false];
    let c = change(&a, &b, &covered, false);
    // Pixel 0 moves 1 level (not more than 2), pixel 1 moves 4 (more than 2), pixel 2 none:
    // one of three covered pixels; pixel 3 (255 levels) is not covered.
    assert_eq!(CHANGE_LEVELS, 2);
    assert!((c.share - 1.0 / 3.0).abs() < 1e-12, "{}", c.share);
    assert_eq!(c.max_levels, 4);
    assert_eq!(c.flip, None);
    let same = change(&a, &a, &covered, true);
    assert_eq!((same.share, same.max_levels, same.flip), (0.0, 0, Some(0.0)));
}

#[test]
fn scores_combine_whole_and_covered() {
    // 2 pixels, the second uncovered and wrong by 0.5 in every channel: covered PSNR and SSIM
    // ignore it; whole-image PSNR is 20 log10(1 / sqrt(0.25 / 2)) = 9.03 dB.
    let reference = image(2, 1, |_| [0.0; 3]);
    let test = image(2, 1, |p| [p as f32 * 0.5; 3]);
    let s = score(&reference, &test, &[true, false], true);
    assert_eq!(s.covered.psnr, f64::INFINITY);
    assert!((s.whole.psnr - 20.0 * (1.0 / 0.125f64.sqrt()).log10()).abs() < 1e-9);
    assert!(s.ssim < s.ssim_covered + 1e-12);
    assert_eq!(s.whole.flip, s.flip_map.as_ref().map(|m| m.mean()));
    assert!(s.flip_covered.is_some());
}

#[test]
fn difference_is_gained_in_linear_light_by_hand() {
    use oit_lab::out::picture::Picture;
    // Errors of 1/255 and 0.1 gained 8x: 8/255 -> byte 8 (sRGB-encoded it would be
    // 1.055 * 0.03137^(1/2.4) - 0.055 = 0.194 -> byte 50), 0.8 -> byte 204; 0.2 gained 8x
    // saturates at 255. Values above 1 are clamped before the difference (no error).
    let reference = image(4, 1, |_| [0.5, 0.5, 1.0]);
    let test = image(4, 1, |p| {
        [
            [0.5 + 1.0 / 255.0, 0.5, 1.0],
            [0.6, 0.5, 1.0],
            [0.7, 0.5, 1.0],
            [0.5, 0.5, 3.0],
        ][p]
    });
    let d = Picture::difference(&reference, &test, 8.0);
    assert_eq!(d.data, vec![8, 0, 0, 204, 0, 0, 255, 0, 0, 0, 0, 0]);
}

#[test]
fn font_draws_the_glyph_bits() {
    use oit_lab::out::picture::{Picture, draw_text, glyph, text_width};
    // 'I' is .###. / ..#.. x5 / .###.; at scale 1 its top row inks columns 1-3, row 1 column 2.
    let mut p = Picture::filled(6, 7, [255; 3]);
    draw_text(&mut p, 0, 0, "I", 1, [0; 3]);
    let ink = |x: u32, y: u32| p.data[((y * 6 + x) * 3) as usize] == 0;
    assert_eq!(
        (0..5).map(|x| ink(x, 0)).collect::<Vec<_>>(),
        [false, true, true, true, false]
    );
    assert_eq!(
        (0..5).map(|x| ink(x, 1)).collect::<Vec<_>>(),
        [false, false, true, false, false]
    );
    // Two characters: 5 + 1 gap + 5 = 11 columns, doubled at scale 2; a space has no ink.
    assert_eq!(text_width("ab", 1), 11);
    assert_eq!(text_width("ab", 2), 22);
    assert_eq!(glyph(' '), [0; 7]);
    // Every character of the figure's labels has its own glyph (not the '?' fallback).
    for c in "|=+-/()[]%:.,'x0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz".chars() {
        assert!(c == '?' || glyph(c) != glyph('?'), "{c}");
    }
}

#[test]
fn densest_window_by_hand() {
    use oit_lab::out::picture::densest;
    // 16x8 counts, all 1 except a 4x4 block of 9 at (8, 4): the 4x4 window on the 4-pixel
    // grid with the most fragments is that block (144 against at most 16 elsewhere).
    let mut counts = vec![1u32; 16 * 8];
    for y in 4..8 {
        for x in 8..12 {
            counts[y * 16 + x] = 9;
        }
    }
    assert_eq!(densest(&counts, 16, 8, 4, 4), (8, 4, 4, 4));
}
