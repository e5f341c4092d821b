//! Scene-file messages name the full key path of what is wrong — the entry, the key, the
//! element of a vector — and keys of another shape or light type say they do not apply.

use luxtally::scene::load_str;
use std::path::Path;

const GREY: &str = "[materials.grey]\nreflectance = 0.5\n";

fn error_of(body: &str) -> String {
    match load_str(&format!("{GREY}{body}"), Path::new("."), "test.toml") {
        Ok(_) => panic!("accepted:\n{body}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn messages_name_the_key_path_down_to_the_vector_element() {
    let sphere = "[[objects]]\nshape = \"sphere\"\nmaterial = \"grey\"\n";
    let cases: &[(String, &[&str])] = &[
        (
            format!("{sphere}center = [0, \"a\", 0]\nradius = 1\n"),
            &["test.toml: objects[0].center[1]:", "expected f64"],
        ),
        (
            format!("{sphere}center = [0, 0, 0]\nradius = \"big\"\n"),
            &["test.toml: objects[0].radius:", "expected f64"],
        ),
        (
            format!("{sphere}center = [0, 0, 0]\nradius = 1\ninstances = [{{scale = \"x\"}}]\n"),
            &["objects[0].instances[0].scale:", "a number or an array of 3 numbers"],
        ),
        (
            "[[lights]]\ntype = \"point\"\nposition = [0, 0, \"a\"]\nintensity_cd = 1\n".into(),
            &["test.toml: lights[0].position[2]:", "expected f64"],
        ),
        (
            "[[receivers]]\nname = \"r\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\ncells = [2, 2]\nestimator = \"fast\"\n".into(),
            &["test.toml: receivers[0].estimator:", "`fast`", "`next_event`"],
        ),
        (
            "[[receivers]]\nname = \"r\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\ncells = [2, 2]\nquantity = \"flux\"\n".into(),
            &["test.toml: receivers[0].quantity:", "`flux`", "`luminance`"],
        ),
        (
            "[camera]\nposition = [0, 0, 0]\nlook_at = [1, 0, 0]\nfov_deg = 40\nresolution = [10, 10]\nzoom = 2\n".into(),
            &["test.toml: camera.zoom:", "unknown field `zoom`"],
        ),
        (
            "[materials.x]\nreflectance = \"a\"\n".into(),
            &["test.toml: materials.x.reflectance:", "expected f64"],
        ),
    ];
    for (body, expected) in cases {
        let m = error_of(body);
        for e in *expected {
            assert!(m.contains(e), "`{m}` lacks `{e}`");
        }
        assert!(!m.contains('\n'), "one line: {m}");
    }
}

#[test]
fn keys_of_another_kind_do_not_apply_and_unknown_keys_are_named() {
    let cases: &[(&str, &str)] = &[
        (
            "[[objects]]\nfile = \"x.obj\"\nradius = 2\n",
            "test.toml: objects[0].radius: does not apply to a mesh file",
        ),
        (
            "[[objects]]\nshape = \"rect\"\nmaterial = \"grey\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\nradius = 1\n",
            "test.toml: objects[0].radius: does not apply to shape \"rect\"",
        ),
        (
            "[[objects]]\nshape = \"box\"\nmaterial = \"grey\"\nmin = [0, 0, 0]\nmax = [1, 1, 1]\ncolour = 2\n",
            "test.toml: objects[0].colour: unknown field `colour` for shape \"box\" (expected one of `min`, `max`)",
        ),
        (
            "[[lights]]\ntype = \"directional\"\ndirection = [0, 0, -1]\nilluminance_lx = 1\ncone_deg = 3\n",
            "test.toml: lights[0].cone_deg: does not apply to type \"directional\" lights",
        ),
        (
            "[[lights]]\ntype = \"point\"\nposition = [0, 0, 0]\nintensity_cd = 1\ncolour = 3\n",
            "test.toml: lights[0].colour: unknown field `colour` for type \"point\" lights",
        ),
        (
            "[[lights]]\nposition = [0, 0, 0]\n",
            "test.toml: lights[0].type: missing (expected \"point\", \"spot\", \"directional\", \"area\", \"luminaire\", \"sky\" or \"sun\")",
        ),
    ];
    for (body, expected) in cases {
        let m = error_of(body);
        assert!(m.starts_with(expected), "`{m}` is not `{expected}…`");
    }
}
