//! The documentation as a user meets it: every Rhai snippet of the README and the book runs
//! (at `resolution=smoke`, in a fresh output directory that is also its data directory, so a
//! snippet that writes a data file can read it back), and the book's script reference is the
//! API the binary offers.

mod common;

use common::TempDir;
use std::path::{Path, PathBuf};
use trnews::script::{api_markdown, parse_param_value, Host, HostOptions};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The README and every page of the book.
fn pages() -> Vec<PathBuf> {
    let mut pages = vec![root().join("README.md")];
    let mut dirs = vec![root().join("docs/src")];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(&dir).expect("docs/src exists") {
            let path = entry.expect("dir entry").path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "md") {
                pages.push(path);
            }
        }
    }
    pages.sort();
    pages
}

/// The fenced ```rhai blocks of a page, each with the line its code starts on.
fn rhai_snippets(text: &str) -> Vec<(usize, String)> {
    let mut snippets = Vec::new();
    let mut current: Option<(usize, String)> = None;
    for (i, line) in text.lines().enumerate() {
        let fence = line.trim_start();
        match &mut current {
            None if fence.starts_with("```rhai") => current = Some((i + 2, String::new())),
            Some(_) if fence.starts_with("```") => snippets.extend(current.take()),
            Some((_, code)) => {
                code.push_str(line);
                code.push('\n');
            }
            None => {}
        }
    }
    snippets
}

fn run_snippet(name: &str, code: &str) -> Result<(), String> {
    let dir = TempDir::new("book_snippet");
    let host = Host::new(HostOptions {
        out_dir: dir.path().to_path_buf(),
        data_dir: Some(dir.path().to_path_buf()),
        params: [("resolution".to_string(), parse_param_value("smoke"))].into(),
        quiet: true,
        ..HostOptions::default()
    })
    .map_err(|e| e.to_string())?;
    host.run_str(name, code).map_err(|e| e.to_string())
}

#[test]
fn every_rhai_snippet_in_the_readme_and_the_book_runs() {
    let mut ran = 0;
    let mut failures = Vec::new();
    for page in pages() {
        let text = std::fs::read_to_string(&page).expect("page readable");
        let shown = page
            .strip_prefix(root())
            .unwrap_or(&page)
            .display()
            .to_string();
        for (line, code) in rhai_snippets(&text) {
            let name = format!("{shown}:{line}");
            ran += 1;
            if let Err(e) = run_snippet(&name, &code) {
                failures.push(format!("{name}: {e}"));
            }
        }
    }
    assert!(
        ran >= 3,
        "expected the README's and the guide's snippets, ran {ran}"
    );
    assert!(
        failures.is_empty(),
        "snippets failed:\n{}",
        failures.join("\n")
    );
}

#[test]
fn snippet_extraction_finds_code_and_its_line() {
    let text =
        "# t\n\n```rhai\nlet a = 1;\nprint(a);\n```\ntext\n```sh\nls\n```\n```rhai\nx\n```\n";
    let snippets = rhai_snippets(text);
    assert_eq!(
        snippets,
        vec![
            (4, "let a = 1;\nprint(a);\n".to_string()),
            (12, "x\n".to_string())
        ]
    );
    // a failing snippet is reported, so the test above can fail
    assert!(run_snippet("bad.md:1", "throw \"no\";").is_err());
}

#[test]
fn the_script_reference_is_the_api() {
    let host = Host::new(HostOptions {
        out_dir: TempDir::new("book_reference").path().to_path_buf(),
        quiet: true,
        ..HostOptions::default()
    })
    .expect("host");
    let page = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/src/reference.md");
    let committed = std::fs::read_to_string(&page).unwrap_or_default();
    let generated = api_markdown(&host.api());
    let first_difference = committed
        .lines()
        .zip(generated.lines())
        .position(|(a, b)| a != b)
        .map(|i| format!("line {}: {:?}", i + 1, generated.lines().nth(i)));
    assert!(
        committed == generated,
        "docs/src/reference.md differs from the API ({}): regenerate it with \
         `cargo run --release -- --api markdown > docs/src/reference.md`",
        first_difference.unwrap_or_else(|| "in length".into())
    );
}

#[test]
fn a_parameter_the_script_never_asks_for_is_named() {
    let dir = TempDir::new("book_unread");
    let host = Host::new(HostOptions {
        out_dir: dir.path().to_path_buf(),
        params: [
            ("resolution".to_string(), parse_param_value("smoke")),
            ("resolutoin".to_string(), parse_param_value("paper")),
        ]
        .into(),
        quiet: true,
        ..HostOptions::default()
    })
    .expect("host");
    host.run_str("t.rhai", r#"let r = param("resolution", "quick");"#)
        .expect("runs");
    assert_eq!(host.unread_params(), vec!["resolutoin".to_string()]);
}
