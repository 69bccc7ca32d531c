//! Scenes pinned by a hash of their stream; the dump format round-trips; bad dumps fail.

use oit_lab::dump::{self, DumpError};
use oit_lab::scenes::Scene;
use oit_lab::stream::Stream;

const W: u32 = 64;
const H: u32 = 36;

/// Stream hashes at 64x36, seed 1. A change here means every number in docs/quality.md
/// must be regenerated.
const PINNED: [(Scene, u64); 5] = [
    (Scene::Hair, 0x30c954954e504741),
    (Scene::Particles, 0x3e95706a56b8704f),
    (Scene::Forest, 0x99975b67b8d53ec4),
    (Scene::Teapots, 0x9c1633910248c6f5),
    (Scene::Glass, 0x760e1d1085a9dd51),
];

#[test]
fn scenes_are_pinned() {
    let mut bad = Vec::new();
    for (sc, want) in PINNED {
        let got = sc.generate(W, H, 1).hash();
        if got != want {
            bad.push(format!("{}: {got:#018x}", sc.name()));
        }
    }
    assert!(bad.is_empty(), "scene streams changed: {bad:?}");
}

#[test]
fn scenes_are_deterministic_valid_and_seeded() {
    for sc in Scene::ALL {
        let a = sc.generate(W, H, 1);
        assert_eq!(a, sc.generate(W, H, 1), "{}", sc.name());
        assert!(a.frags.len() > 100, "{}: {} fragments", sc.name(), a.frags.len());
        assert!(a.validate().is_ok(), "{}", sc.name());
        assert!(a.frags.iter().all(|f| f.pixel < W * H));
        assert_ne!(a.hash(), sc.generate(W, H, 2).hash(), "{}: seed ignored", sc.name());
    }
}

#[test]
fn scene_names_parse() {
    for sc in Scene::ALL {
        assert_eq!(Scene::from_name(&sc.name().to_ascii_lowercase()), Some(sc));
    }
    assert_eq!(Scene::from_name("pwrplant"), Some(Scene::Teapots));
    assert_eq!(Scene::from_name("nope"), None);
}

fn sample() -> Stream {
    Scene::Particles.generate(40, 24, 3)
}

#[test]
fn dump_round_trips() {
    let s = sample();
    let bytes = dump::to_bytes(&s);
    assert_eq!(bytes.len(), dump::HEADER + dump::RECORD * s.frags.len());
    assert_eq!(&bytes[..8], b"OITFRAG1");
    assert_eq!(dump::from_bytes(&bytes), Ok(s.clone()));
    let dir = std::env::temp_dir().join(format!("oit-lab-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("p.oitfrag");
    dump::write(&path, &s).unwrap();
    assert_eq!(dump::read(&path), Ok(s));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn dump_layout_is_little_endian() {
    let s = Stream {
        width: 3,
        height: 2,
        background: [1.0, 0.0, 0.5],
        frags: vec![oit_lab::stream::Frag {
            pixel: 5,
            depth: 2.0,
            color: [0.25, 0.0, 0.0],
            alpha: 0.5,
        }],
    };
    let b = dump::to_bytes(&s);
    assert_eq!(&b[8..16], &[3, 0, 0, 0, 2, 0, 0, 0]);
    assert_eq!(&b[16..20], &1.0f32.to_le_bytes());
    assert_eq!(&b[28..36], &[1, 0, 0, 0, 0, 0, 0, 0]);
    // x = 2, y = 1, depth 2.0.
    assert_eq!(&b[36..44], &[2, 0, 0, 0, 1, 0, 0, 0]);
    assert_eq!(&b[44..48], &[0, 0, 0, 0x40]);
}

#[test]
fn bad_dumps_are_errors() {
    let good = dump::to_bytes(&sample());
    let n = (good.len() - dump::HEADER) / dump::RECORD;
    let mut magic = good.clone();
    magic[0] = b'X';
    assert_eq!(dump::from_bytes(&magic), Err(DumpError::BadMagic));
    assert_eq!(dump::from_bytes(b"OIT"), Err(DumpError::BadMagic));
    assert!(matches!(
        dump::from_bytes(&good[..20]),
        Err(DumpError::Truncated { .. })
    ));
    assert!(matches!(
        dump::from_bytes(&good[..good.len() - 1]),
        Err(DumpError::Truncated { .. })
    ));
    let mut long = good.clone();
    long.push(0);
    assert!(matches!(dump::from_bytes(&long), Err(DumpError::TrailingBytes { .. })));
    // A count so large that 36 + 28 n overflows.
    let mut huge = good.clone();
    huge[28..36].copy_from_slice(&u64::MAX.to_le_bytes());
    assert!(matches!(dump::from_bytes(&huge), Err(DumpError::Truncated { .. })));
    let mut zero = good.clone();
    zero[8..12].copy_from_slice(&0u32.to_le_bytes());
    assert!(matches!(dump::from_bytes(&zero), Err(DumpError::BadSize(0, _))));
    let mut bg = good.clone();
    bg[16..20].copy_from_slice(&f32::NAN.to_le_bytes());
    assert_eq!(dump::from_bytes(&bg), Err(DumpError::BadBackground));
    let last = dump::HEADER + (n - 1) * dump::RECORD;
    let mut x = good.clone();
    x[last..last + 4].copy_from_slice(&1000u32.to_le_bytes());
    assert!(matches!(
        dump::from_bytes(&x),
        Err(DumpError::PixelOutOfRange { x: 1000, .. })
    ));
    for (offset, value, error) in [
        (8, f32::NAN, mlab::FragmentError::NanDepth),
        (8, f32::INFINITY, mlab::FragmentError::InfiniteDepth),
        (24, f32::NAN, mlab::FragmentError::NanAlpha),
        (24, 1.5, mlab::FragmentError::AlphaOutOfRange),
        (12, -0.5, mlab::FragmentError::NegativeColor),
        (16, f32::NAN, mlab::FragmentError::NanColor),
    ] {
        let mut b = good.clone();
        b[last + offset..last + offset + 4].copy_from_slice(&value.to_le_bytes());
        assert_eq!(
            dump::from_bytes(&b),
            Err(DumpError::BadFragment {
                index: (n - 1) as u64,
                error
            }),
            "offset {offset} value {value}"
        );
    }
    let missing = dump::read(std::path::Path::new("/nonexistent/oit-lab.dump"));
    assert!(matches!(missing, Err(DumpError::Io(_))));
}
