//! A large Embree build runs with transparent huge pages off and leaves them on, with the
//! BVH collapsed into huge pages in the background (`accel::huge_pages`); a large obvhs
//! BVH is collapsed after its build too. One test: the
//! switch is process-wide, so its cases must not run concurrently.

use luxtally::accel::embree::EmbreeScene;
use luxtally::accel::huge_pages::{
    anon_huge_bytes, can_collapse, huge_pages_enabled, set_huge_pages, wait_for_collapse,
    DEFER_FROM_TRIANGLES,
};
use luxtally::fixtures::procedural_geometry;

#[test]
fn large_builds_defer_huge_pages_and_leave_them_on() {
    if !huge_pages_enabled() {
        eprintln!("skipped: this process was started with transparent huge pages off");
        return;
    }
    // 2²⁰ triangles: a BVH of ≈ 60 MiB.
    let geometry = procedural_geometry(DEFER_FROM_TRIANGLES.max(1 << 20));

    // A small build leaves everything alone.
    drop(EmbreeScene::new(&procedural_geometry(1000)).unwrap());
    assert!(huge_pages_enabled());
    assert_eq!(wait_for_collapse(), None, "a small build collapses nothing");

    // A large one: huge pages on afterwards; where the kernel can collapse, the BVH is
    // collapsed into huge pages in the background.
    let before = anon_huge_bytes();
    let scene = EmbreeScene::new(&geometry).unwrap();
    assert!(
        huge_pages_enabled(),
        "huge pages must be on after the build"
    );
    let collapse = wait_for_collapse();
    if !can_collapse() {
        assert_eq!(
            collapse, None,
            "nothing to collapse where the kernel cannot"
        );
        eprintln!("this kernel cannot collapse memory into huge pages: build not deferred");
        return;
    }
    let collapse = collapse.expect("a large build starts a collapse");
    assert!(
        collapse.regions >= 1,
        "Embree asked for huge pages: {collapse:?}"
    );
    assert!(
        collapse.huge_bytes >= before + (32 << 20),
        "the BVH is not in huge pages: {before} bytes before, {collapse:?}"
    );
    drop(scene);

    // The obvhs BVH (4 KiB pages as built) is advised and collapsed after its build.
    #[cfg(feature = "obvhs")]
    {
        let before = anon_huge_bytes();
        let scene = luxtally::accel::obvhs::ObvhsScene::new(&geometry);
        let collapse = wait_for_collapse().expect("a large obvhs build starts a collapse");
        assert!(
            collapse.huge_bytes >= before + (32 << 20),
            "the obvhs BVH is not in huge pages: {before} bytes before, {collapse:?}"
        );
        drop(scene);
    }

    // A process that had huge pages off keeps them off, and nothing is collapsed.
    assert!(set_huge_pages(false));
    drop(EmbreeScene::new(&geometry).unwrap());
    #[cfg(feature = "obvhs")]
    drop(luxtally::accel::obvhs::ObvhsScene::new(&geometry));
    assert!(!huge_pages_enabled(), "the process's own choice must stand");
    assert_eq!(wait_for_collapse(), None);
    assert!(set_huge_pages(true));
}
