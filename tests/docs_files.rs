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
