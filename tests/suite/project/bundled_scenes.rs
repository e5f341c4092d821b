//! What every bundled scene must carry: it loads, and it has a `[camera]`, so that
//! `luxtally render` can show any of them as an image.

use std::path::Path;

#[test]
fn every_bundled_scene_loads_and_has_a_camera() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut scenes: Vec<_> = std::fs::read_dir(&dir)
        .expect("scenes/")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 4, "{scenes:?}");
    for path in scenes {
        let scene = luxtally::scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        assert!(scene.camera.is_some(), "{} has no [camera]", path.display());
    }
}
