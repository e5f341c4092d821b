//! A large Embree build runs with transparent huge pages off and leaves them on, with the
//! BVH collapsed into huge pages in the background (`accel::huge_pages`). One test: the
//! switch is process-wide, so its cases must not run concurrently.

use luxtally::accel::embree::EmbreeScene;
use luxtally::accel::huge_pages::{
    huge_pages_enabled, set_huge_pages, wait_for_collapse, DEFER_FROM_TRIANGLES,
};
use luxtally::bench::procedural_geometry;

fn huge_pages_disabled() -> bool {
    !huge_pages_enabled()
}

fn set_huge_pages_disabled(off: bool) {
    assert!(set_huge_pages(!off), "prctl(PR_SET_THP_DISABLE) failed");
}

/// Bytes of the process's anonymous memory in huge pages.
fn anon_huge_bytes() -> u64 {
    let text = std::fs::read_to_string("/proc/self/smaps_rollup").expect("smaps_rollup");
    let line = text
        .lines()
        .find(|l| l.starts_with("AnonHugePages:"))
        .expect("AnonHugePages line");
    let kib: u64 = line.split_whitespace().nth(1).unwrap().parse().unwrap();
    kib * 1024
}

/// Whether the kernel has `MADV_COLLAPSE` (Linux 6.1).
fn kernel_can_collapse() -> bool {
    let release = std::fs::read_to_string("/proc/sys/kernel/osrelease").unwrap_or_default();
    let mut parts = release
        .trim()
        .split(['.', '-'])
        .map(|p| p.parse::<u32>().unwrap_or(0));
    (parts.next().unwrap_or(0), parts.next().unwrap_or(0)) >= (6, 1)
}

#[test]
fn large_builds_defer_huge_pages_and_leave_them_on() {
    let geometry = procedural_geometry(DEFER_FROM_TRIANGLES);
    assert!(
        !huge_pages_disabled(),
        "the test process starts with huge pages on"
    );

    // A small build leaves everything alone.
    let small = procedural_geometry(1000);
    drop(EmbreeScene::new(&small).unwrap());
    assert!(!huge_pages_disabled());
    assert_eq!(wait_for_collapse(), None, "a small build collapses nothing");

    // A large one: huge pages back on afterwards, the BVH collapsed in the background.
    let before = anon_huge_bytes();
    let scene = EmbreeScene::new(&geometry).unwrap();
    assert!(
        !huge_pages_disabled(),
        "huge pages must be back on after the build"
    );
    let collapse = wait_for_collapse().expect("a large build starts a collapse");
    assert!(
        collapse.regions >= 1,
        "Embree asked for huge pages: {collapse:?}"
    );
    if kernel_can_collapse() {
        assert!(collapse.bytes_collapsed >= 32 << 20, "{collapse:?}");
        assert!(
            anon_huge_bytes() >= before + (32 << 20),
            "the BVH is not in huge pages: {} → {} bytes",
            before,
            anon_huge_bytes()
        );
    }
    drop(scene);

    // A process that had huge pages off keeps them off, and nothing is collapsed.
    set_huge_pages_disabled(true);
    drop(EmbreeScene::new(&geometry).unwrap());
    assert!(huge_pages_disabled(), "the process's own choice must stand");
    assert_eq!(wait_for_collapse(), None);
    set_huge_pages_disabled(false);
}
