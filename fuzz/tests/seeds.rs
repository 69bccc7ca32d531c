//! Replay the committed seeds (`corpus/<target>/seed-*`) through every target without
//! libFuzzer: `cargo test --manifest-path fuzz/Cargo.toml`. A failing seed names itself.

use std::path::Path;

fn replay(target: &str, run: fn(&[u8])) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("corpus").join(target);
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).expect("corpus dir") {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if !name.starts_with("seed-") {
            continue;
        }
        let data = std::fs::read(&path).unwrap();
        eprintln!("{target}/{name}");
        run(&data);
        n += 1;
    }
    assert!(n > 0, "no seeds in {}", dir.display());
}

#[test]
fn mlab_stream_seeds() {
    replay("mlab_stream", mlab_fuzz::targets::mlab_stream::mlab_stream);
}

#[test]
fn hybrid_stream_seeds() {
    replay("hybrid_stream", mlab_fuzz::targets::hybrid_stream::hybrid_stream);
}

#[test]
fn rows_from_bytes_seeds() {
    replay("rows_from_bytes", mlab_fuzz::targets::rows_from_bytes::rows_from_bytes);
}

#[test]
fn lanes_masks_seeds() {
    replay("lanes_masks", mlab_fuzz::targets::lanes_masks::lanes_masks);
}

#[test]
fn batch_stream_seeds() {
    replay("batch_stream", mlab_fuzz::batch::batch_stream);
}
