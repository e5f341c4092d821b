//! The library's layering, as src/lib.rs states it ("Layering: … `error`, `rng` … →
//! `fixtures`"): each module uses only modules listed before it, never one after it, so
//! there is no import cycle. Unit tests (`#[cfg(test)]` to the end of a file) may use
//! anything. docs/architecture.md repeats the list; the two must agree.

use std::path::Path;

/// The backticked names of the paragraph of `text` that starts at `marker`.
fn listed_modules(text: &str, marker: &str) -> Vec<String> {
    let start = text.find(marker).unwrap_or_else(|| panic!("no `{marker}`"));
    let paragraph: String = text[start..]
        .lines()
        .map(|l| l.trim_start_matches("//!").trim())
        .take_while(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ");
    let order = paragraph
        .split_once(':')
        .map_or(paragraph.as_str(), |(_, rest)| rest);
    order
        .split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .filter(|name| {
            Path::new("src").join(format!("{name}.rs")).exists()
                || Path::new("src").join(name).is_dir()
        })
        .collect()
}

fn lib_order() -> Vec<String> {
    let lib = std::fs::read_to_string("src/lib.rs").unwrap();
    listed_modules(&lib, "Layering:")
}

/// Every `.rs` file of module `name`, without its unit tests.
fn module_sources(name: &str) -> Vec<(String, String)> {
    let mut files = Vec::new();
    let single = Path::new("src").join(format!("{name}.rs"));
    let mut dirs = vec![Path::new("src").join(name)];
    if single.exists() {
        files.push(single);
    }
    while let Some(dir) = dirs.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries {
            let path = entry.unwrap().path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                files.push(path);
            }
        }
    }
    files
        .into_iter()
        .map(|path| {
            let text = std::fs::read_to_string(&path).unwrap();
            let code = text.split("#[cfg(test)]").next().unwrap_or("").to_string();
            (path.display().to_string(), code)
        })
        .collect()
}

/// The modules `code` names as `crate::NAME`.
fn used_modules(code: &str) -> Vec<String> {
    code.match_indices("crate::")
        .map(|(at, _)| {
            code[at + 7..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect::<String>()
        })
        .filter(|name| !name.is_empty() && name.chars().next().unwrap().is_ascii_lowercase())
        .collect()
}

#[test]
fn no_module_uses_one_listed_after_it() {
    let order = lib_order();
    assert!(order.len() >= 15, "layering list: {order:?}");
    let lib = std::fs::read_to_string("src/lib.rs").unwrap();
    for line in lib.lines().filter(|l| l.starts_with("pub mod ")) {
        let name = line.trim_start_matches("pub mod ").trim_end_matches(';');
        assert!(
            order.iter().any(|m| m == name),
            "src/lib.rs's layering leaves out `{name}`"
        );
    }
    let mut violations = Vec::new();
    for (rank, module) in order.iter().enumerate() {
        for (file, code) in module_sources(module) {
            for used in used_modules(&code) {
                match order.iter().position(|m| *m == used) {
                    Some(r) if r > rank => violations.push(format!("{file} uses `{used}`")),
                    _ => {}
                }
            }
        }
    }
    assert!(
        violations.is_empty(),
        "modules using ones listed after them (src/lib.rs's order): {violations:#?}"
    );
}

#[test]
fn the_architecture_page_lists_the_same_layering() {
    let page = std::fs::read_to_string("docs/architecture.md").unwrap();
    let section = &page[page.find("### Layering").expect("a Layering section")..];
    let start = section.find("\n`").expect("the list") + 1;
    let page_order = listed_modules(&section[start..], "`");
    assert_eq!(
        page_order,
        lib_order(),
        "docs/architecture.md against src/lib.rs"
    );
}
