//! `oit-lab peers` on tiny frames: the camera path, its flicker measure, the budget choice.

use oit_lab::methods::Method;
use oit_lab::methods::catalog::bounded;
use oit_lab::out::table::median;
use oit_lab::scenes::Scene;
use oit_lab::study::peers::{CAMERA_FRAMES, best_within, camera_flicker, camera_stream};
use oit_lab::study::sweep::{Plan, run_scene};

#[test]
fn camera_path_starts_at_the_scene_and_moves() {
    let (w, h) = (48, 27);
    let f0 = camera_stream(Scene::Glass, (w, h), 1, 0);
    assert_eq!(f0, Scene::Glass.generate(w, h, 1), "frame 0 is the scene itself");
    let f5 = camera_stream(Scene::Glass, (w, h), 1, 5);
    assert_eq!((f5.width, f5.height), (w, h));
    assert!(f5.frags.iter().all(|f| f.pixel < w * h));
    assert!(f5.validate().is_ok());
    assert_ne!(f5, f0, "the camera moved");
    assert_eq!(f5, camera_stream(Scene::Glass, (w, h), 1, 5), "seeded");
    assert_ne!(
        camera_stream(Scene::Glass, (w, h), 2, 5).frags,
        f5.frags,
        "another seed, another scene and path"
    );
}

#[test]
fn flicker_is_measured_against_the_reference() {
    let methods = [Method::Reference, Method::Mlab(16), Method::Over];
    let fl = camera_flicker(Scene::Glass, (48, 27), 1, &methods).unwrap();
    assert!(fl.iter().all(|f| f.share.len() == CAMERA_FRAMES - 1));
    // The reference against itself: nothing beyond its own change, which is the scene's.
    assert!(fl[0].mean.iter().all(|&x| x == 0.0) && fl[0].share.iter().all(|&x| x == 0.0));
    assert!(fl[0].own.iter().any(|&x| x > 0.0), "the scene changes on screen");
    // MLAB 16 never merges on GLASS (at most 8 fragments a pixel): it follows the reference
    // within 8-bit rounding; unsorted OVER does not.
    assert!(median(&fl[1].share) < 0.01, "{:?}", fl[1].share);
    assert!(
        median(&fl[2].share) > median(&fl[1].share) + 0.02,
        "{:?} vs {:?}",
        fl[2].share,
        fl[1].share
    );
}

#[test]
fn budget_choice_is_the_best_that_fits() {
    let mut methods = vec![Method::Reference];
    methods.extend(bounded());
    let plan = Plan {
        size: (48, 27),
        seeds: vec![1],
        orders: 2,
        methods,
        with_flip: true,
        pair_flip: Vec::new(),
        strip: None,
    };
    let sc = run_scene(Scene::Teapots, &plan, |_, _| {}).unwrap();
    let psnr = |m: Method| {
        let r = sc.runs.iter().find(|r| r.method == m).unwrap();
        (r.bytes, median(&r.samples.iter().map(|s| s.psnr).collect::<Vec<_>>()))
    };
    for budget in [8, 16, 32, 64] {
        let (bp, _) = best_within(&sc, budget).unwrap();
        let (bytes, best) = psnr(bp);
        assert!(bytes <= budget as f64, "{} fits {budget}", bp.name());
        for m in bounded() {
            let (b, p) = psnr(m);
            assert!(
                b > budget as f64 || p <= best,
                "{} ({p}) beats {} ({best}) at {budget}",
                m.name(),
                bp.name()
            );
        }
    }
    // The A-buffer never wins a budget (it is not bounded).
    assert!(best_within(&sc, 1 << 20).is_some_and(|(p, f)| p != Method::Reference && f != Method::Reference));
}
