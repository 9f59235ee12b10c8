//! Every relative link and picture in README.md and docs/*.md leads somewhere: the file exists,
//! and a `#anchor` names a heading of the page it points to (GitHub's heading anchors).

use std::path::{Path, PathBuf};

// the repository root
fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

// GitHub's anchor of a heading: lower case, letters, digits, `-` and `_` kept, spaces to `-`,
// everything else dropped
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

// the anchors of a Markdown page's headings (outside code blocks)
fn anchors(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut code = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            code = !code;
        } else if !code && line.starts_with('#') {
            out.push(slug(line.trim_start_matches('#')));
        }
    }
    out
}

// the targets of `[text](target)` and `![alt](target)` links, outside code blocks and spans
fn links(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut code = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            code = !code;
            continue;
        }
        if code {
            continue;
        }
        for (i, part) in line.split('`').enumerate() {
            if i % 2 == 1 {
                continue;
            }
            let mut rest = part;
            while let Some(at) = rest.find("](") {
                let after = &rest[at + 2..];
                let end = after.find(')').unwrap_or(after.len());
                out.push(after[..end].to_string());
                rest = &after[end..];
            }
        }
    }
    out
}

// the problems of one page's links
fn check(page: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(page).unwrap();
    let dir = page.parent().unwrap();
    let mut bad = Vec::new();
    for target in links(&text) {
        if target.starts_with("http://") || target.starts_with("https://") || target.starts_with("mailto:") {
            continue;
        }
        let (file, anchor) = target.split_once('#').map_or((target.as_str(), None), |(f, a)| (f, Some(a)));
        let path = if file.is_empty() { page.to_path_buf() } else { dir.join(file) };
        if !path.exists() {
            bad.push(format!("{}: {target}: no such file", page.display()));
            continue;
        }
        if let Some(anchor) = anchor {
            let heads = anchors(&std::fs::read_to_string(&path).unwrap_or_default());
            if !heads.iter().any(|h| h == anchor) {
                bad.push(format!("{}: {target}: no such heading (has {heads:?})", page.display()));
            }
        }
    }
    bad
}

#[test]
fn every_link_in_the_readme_and_the_docs_leads_somewhere() {
    let mut pages = vec![root().join("README.md")];
    for e in std::fs::read_dir(root().join("docs")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "md") {
            pages.push(p);
        }
    }
    let bad: Vec<String> = pages.iter().flat_map(|p| check(p)).collect();
    assert!(bad.is_empty(), "{}", bad.join("\n"));
    // the README links every docs page
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    for p in &pages[1..] {
        let name = format!("docs/{}", p.file_name().unwrap().to_string_lossy());
        assert!(readme.contains(&format!("]({name})")), "README does not link {name}");
    }
}

#[test]
fn slugs_follow_github() {
    assert_eq!(slug(" DMA burst mode (`$581=1`)"), "dma-burst-mode-5811");
    assert_eq!(slug("How a move's speed is limited"), "how-a-moves-speed-is-limited");
    assert_eq!(slug("1. Make the firmware files"), "1-make-the-firmware-files");
}
