//! The files the documentation shows are the files that run: a fenced block in the README (or a
//! page of docs/) right after a `<!-- file: PATH -->` line must be PATH's text, whole. The
//! cluster scripts are shown this way and submitted as they are by `cluster/test`.

use std::path::Path;

/// (document, path named, the block's text) for every marked block.
fn shown_files(document: &Path) -> Vec<(String, String)> {
    let text = std::fs::read_to_string(document).unwrap();
    let mut shown = Vec::new();
    let mut lines = text.lines();
    while let Some(line) = lines.next() {
        let Some(path) = line
            .trim()
            .strip_prefix("<!-- file:")
            .and_then(|rest| rest.strip_suffix("-->"))
        else {
            continue;
        };
        let fence = lines.next().unwrap_or_default();
        assert!(
            fence.starts_with("```"),
            "{}: the line after `{line}` must open a fenced block",
            document.display()
        );
        let mut block = String::new();
        for line in lines.by_ref().take_while(|l| !l.starts_with("```")) {
            block.push_str(line);
            block.push('\n');
        }
        shown.push((path.trim().to_string(), block));
    }
    shown
}

#[test]
fn the_files_shown_are_the_files_that_run() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut documents = vec![root.join("README.md")];
    if let Ok(pages) = std::fs::read_dir(root.join("docs")) {
        documents.extend(
            pages
                .map(|p| p.unwrap().path())
                .filter(|p| p.extension().is_some_and(|e| e == "md")),
        );
    }
    let mut checked = 0;
    for document in &documents {
        for (path, block) in shown_files(document) {
            let file = std::fs::read_to_string(root.join(&path))
                .unwrap_or_else(|e| panic!("{}: shows {path}: {e}", document.display()));
            assert_eq!(
                block,
                file,
                "{} shows {path} other than it is: copy the file into the block",
                document.display()
            );
            checked += 1;
        }
    }
    // the README shows the batch array job and the search's submission script
    assert!(checked >= 2, "only {checked} files shown");
}

/// docs/validation.md names the test of every case V1–V21: each case is listed once, and each test
/// it names (`file::function`, or a bare function continuing the file before it; `…` abbreviates a
/// name by its start) is a test function in that file.
#[test]
fn the_validation_page_names_tests_that_exist() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let page = std::fs::read_to_string(root.join("docs/validation.md")).unwrap();
    let mut cases = Vec::new();
    for row in page.lines().filter(|l| l.starts_with("| V")) {
        let cells: Vec<&str> = row.trim_matches('|').split(" | ").map(str::trim).collect();
        cases.push(cells[0].to_string());
        let mut file = String::new();
        for name in cells[3].split('`').skip(1).step_by(2) {
            let function = match name.split_once("::") {
                Some((f, function)) => {
                    file = f.to_string();
                    function
                }
                None => name,
            };
            assert!(
                !file.is_empty(),
                "{}: no test file before `{name}`",
                cells[0]
            );
            let source = std::fs::read_to_string(root.join(format!("tests/{file}.rs")))
                .unwrap_or_else(|e| panic!("{}: tests/{file}.rs: {e}", cells[0]));
            let found = match function.strip_suffix('…') {
                Some(start) => source.contains(&format!("fn {start}")),
                None => source.contains(&format!("fn {function}(")),
            };
            assert!(
                found,
                "{}: no test `{function}` in tests/{file}.rs",
                cells[0]
            );
        }
    }
    let expected: Vec<String> = (1..=21).map(|k| format!("V{k}")).collect();
    assert_eq!(
        cases, expected,
        "docs/validation.md lists each case once, in order"
    );
}
