//! Every relative link in the documentation resolves: README.md, CHANGELOG.md and docs/*.md.
//!
//! A link `[text](target)` or image `![alt](target)` (and a reference definition
//! `[label]: target`) must name an existing file or folder, relative to the page that holds it;
//! a `#fragment` into a Markdown page must name one of its headings, by GitHub's anchor rules
//! (lowercase, punctuation other than `-` and `_` dropped, spaces → `-`, repeats `-1`, `-2`, …).
//! Links in fenced code blocks, inline code and HTML comments are not links. External
//! `http(s)://` and `mailto:` links are skipped: the test needs no network.

use std::collections::HashMap;
use std::fs;
use std::path::{Component, Path, PathBuf};

/// The workspace root (the parent of `xtask/`).
fn root() -> PathBuf {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    manifest.parent().map(PathBuf::from).unwrap_or(manifest)
}

/// The pages checked, relative to the root.
fn pages(root: &Path) -> Vec<PathBuf> {
    let mut pages = vec![PathBuf::from("README.md"), PathBuf::from("CHANGELOG.md")];
    let mut docs: Vec<PathBuf> = fs::read_dir(root.join("docs"))
        .map(|entries| {
            entries
                .filter_map(|entry| entry.ok())
                .map(|entry| entry.path())
                .filter(|path| path.extension().is_some_and(|ext| ext == "md"))
                .filter_map(|path| path.strip_prefix(root).ok().map(Path::to_path_buf))
                .collect()
        })
        .unwrap_or_default();
    docs.sort();
    pages.extend(docs);
    pages
}

/// The README is a screen, not a notebook: measurements and explanations live in docs/.
const README_MAX_BYTES: u64 = 10 * 1024;

#[test]
fn the_readme_fits_on_a_screen_and_the_changelog_exists() {
    let root = root();
    let readme = std::fs::metadata(root.join("README.md")).expect("README.md");
    assert!(
        readme.len() <= README_MAX_BYTES,
        "README.md is {} bytes, over {README_MAX_BYTES}: move details into docs/*.md and link them",
        readme.len()
    );
    let changelog = std::fs::read_to_string(root.join("CHANGELOG.md")).expect("CHANGELOG.md");
    assert!(
        changelog.contains("## [Unreleased]"),
        "CHANGELOG.md has no `## [Unreleased]` section: add one (Keep a Changelog)"
    );
}

#[test]
fn every_relative_link_in_the_docs_resolves() {
    let root = root();
    let pages = pages(&root);
    assert!(
        pages.iter().any(|page| page.starts_with("docs")),
        "no docs/*.md found under {}",
        root.display()
    );
    let mut problems = Vec::new();
    for page in &pages {
        let text = match fs::read_to_string(root.join(page)) {
            Ok(text) => text,
            Err(e) => {
                problems.push(format!("{}: cannot be read: {e}", page.display()));
                continue;
            }
        };
        problems.extend(check_page(&root, page, &text));
    }
    assert!(
        problems.is_empty(),
        "{} broken link(s) in the docs:\n{}\n\nFix the link (or create what it names), or \
         remove it; a heading's anchor is its text in lowercase, punctuation dropped, spaces as `-`.",
        problems.len(),
        problems.join("\n")
    );
}

#[test]
fn a_broken_link_is_reported() {
    let root = root();
    let page = Path::new("docs/made_up.md");
    let text = "\
# A made-up page

## Twice
## Twice

See [the README](../README.md) and [a page that is not there](no_such_page.md),
![a picture that is not there](img/no_such_picture.png) and [an anchor](#twice-1),
[a missing anchor](#thrice), [the web](https://example.invalid/x) and
[a heading elsewhere](../README.md#no-such-heading-anywhere).

`[inline code](not_a_link.md)` is code.

```text
[in a fence](not_a_link_either.md)
```

<!-- [in a comment](nor_this.md) -->
[label]: missing_reference_target.md
";
    let problems = check_page(&root, page, text);
    let expected = [
        ("docs/made_up.md:6:", "no_such_page.md"),
        ("docs/made_up.md:7:", "img/no_such_picture.png"),
        ("docs/made_up.md:8:", "#thrice"),
        (
            "docs/made_up.md:9:",
            "../README.md#no-such-heading-anywhere",
        ),
        ("docs/made_up.md:18:", "missing_reference_target.md"),
    ];
    assert_eq!(problems.len(), expected.len(), "reported: {problems:#?}");
    for ((place, link), problem) in expected.iter().zip(&problems) {
        assert!(
            problem.starts_with(place) && problem.contains(&format!("`{link}`")),
            "expected {place} … `{link}`, got: {problem}"
        );
    }
    assert!(problems[0].contains("no such file"), "{}", problems[0]);
    assert!(problems[2].contains("no heading"), "{}", problems[2]);
}

#[test]
fn anchors_follow_github() {
    let text = "\
# The closed loop and `cargo xtask demo`
## Fault injection (`host_can::faulty_bus`)
## Body height: not met as specified
## Speed
### Speed
Setext heading
--------------
```
# not a heading
```
";
    let anchors = anchors(text);
    for anchor in [
        "the-closed-loop-and-cargo-xtask-demo",
        "fault-injection-host_canfaulty_bus",
        "body-height-not-met-as-specified",
        "speed",
        "speed-1",
        "setext-heading",
    ] {
        assert!(
            anchors.contains(&anchor.to_owned()),
            "{anchor} in {anchors:?}"
        );
    }
    assert!(!anchors.contains(&"not-a-heading".to_owned()));
    assert_eq!(slug("Wheels & legs — 2× (W/S)"), "wheels--legs--2-ws");
}

/// The broken links of `text`, the page at `page` (relative to `root`), one message each:
/// `page:line: link `target`: what is wrong`.
fn check_page(root: &Path, page: &Path, text: &str) -> Vec<String> {
    let dir = page.parent().unwrap_or(Path::new(""));
    let mut anchors_of: HashMap<PathBuf, Option<Vec<String>>> = HashMap::new();
    let mut problems = Vec::new();
    for (line, target) in links(text) {
        let target = target.trim_matches(|c| c == '<' || c == '>');
        if target.is_empty()
            || ["http://", "https://", "mailto:"]
                .iter()
                .any(|scheme| target.starts_with(scheme))
        {
            continue;
        }
        let (path_part, fragment) = match target.split_once('#') {
            Some((path, fragment)) => (path, Some(fragment)),
            None => (target, None),
        };
        let path_part = percent_decode(path_part);
        let resolved = if path_part.is_empty() {
            page.to_path_buf()
        } else if let Some(from_root) = path_part.strip_prefix('/') {
            normalise(Path::new(from_root))
        } else {
            normalise(&dir.join(&path_part))
        };
        let report = |what: String| format!("{}:{line}: link `{target}`: {what}", page.display());
        if resolved.components().next() == Some(Component::ParentDir) {
            problems.push(report(format!(
                "leaves the repository; link to a file inside it (relative to {})",
                dir.display()
            )));
            continue;
        }
        if !path_part.is_empty() && !root.join(&resolved).exists() {
            problems.push(report(format!(
                "no such file or folder `{}` (paths are relative to the page's folder `{}`); fix the path \
                 or create the file",
                resolved.display(),
                if dir.as_os_str().is_empty() { Path::new(".") } else { dir }.display()
            )));
            continue;
        }
        let Some(fragment) = fragment.filter(|f| !f.is_empty()) else {
            continue;
        };
        if resolved.extension().is_none_or(|ext| ext != "md") {
            continue; // e.g. `#L10` into a source file: GitHub's, not a heading
        }
        let known = anchors_of.entry(resolved.clone()).or_insert_with(|| {
            if resolved == page {
                Some(anchors(text))
            } else {
                fs::read_to_string(root.join(&resolved))
                    .ok()
                    .map(|t| anchors(&t))
            }
        });
        let fragment = percent_decode(fragment).to_lowercase();
        match known {
            Some(known) if known.contains(&fragment) => {}
            Some(known) => problems.push(report(format!(
                "no heading in `{}` has the anchor `#{fragment}`; use one of: {}",
                resolved.display(),
                known.join(", ")
            ))),
            None => problems.push(report(format!("`{}` cannot be read", resolved.display()))),
        }
    }
    problems
}

/// `path` with `.` and `a/..` removed (a leading `..` stays).
fn normalise(path: &Path) -> PathBuf {
    let mut parts: Vec<Component> = Vec::new();
    for part in path.components() {
        match part {
            Component::CurDir => {}
            Component::ParentDir if matches!(parts.last(), Some(Component::Normal(_))) => {
                parts.pop();
            }
            other => parts.push(other),
        }
    }
    parts.iter().collect()
}

fn percent_decode(text: &str) -> String {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            let hex = std::str::from_utf8(&bytes[i + 1..i + 3]).ok();
            if let Some(byte) = hex.and_then(|hex| u8::from_str_radix(hex, 16).ok()) {
                out.push(byte);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// The text outside fenced code blocks, line by line (fence lines and their contents blank),
/// so that line numbers stay those of the file.
fn prose_lines(text: &str) -> Vec<&str> {
    let mut fence: Option<(char, usize)> = None;
    text.lines()
        .map(|line| {
            let trimmed = line.trim_start();
            let marker = trimmed.chars().next().filter(|c| *c == '`' || *c == '~');
            let run = marker.map_or(0, |c| trimmed.chars().take_while(|x| *x == c).count());
            match (fence, marker) {
                (None, Some(c)) if run >= 3 => {
                    fence = Some((c, run));
                    ""
                }
                (Some((c, n)), Some(m))
                    if m == c && run >= n && trimmed[run * c.len_utf8()..].trim().is_empty() =>
                {
                    fence = None;
                    ""
                }
                (Some(_), _) => "",
                (None, _) => line,
            }
        })
        .collect()
}

/// The link targets of `text` with their line numbers (1-based): `[text](target)`,
/// `![alt](target)` and `[label]: target`, outside code and HTML comments.
fn links(text: &str) -> Vec<(usize, String)> {
    let prose = prose_lines(text).join("\n");
    let chars: Vec<char> = prose.chars().collect();
    let mut found = Vec::new();
    let mut line = 1;
    let mut i = 0;
    let mut line_start = true;
    while i < chars.len() {
        let c = chars[i];
        if c == '\n' {
            line += 1;
            line_start = true;
            i += 1;
            continue;
        }
        // Inline code: a run of backticks up to the same run, within the paragraph.
        if c == '`' {
            let run = chars[i..].iter().take_while(|x| **x == '`').count();
            if let Some(end) = closing_backticks(&chars, i + run, run) {
                line += chars[i..end].iter().filter(|x| **x == '\n').count();
                i = end;
            } else {
                i += run;
            }
            line_start = false;
            continue;
        }
        if chars[i..].starts_with(&['<', '!', '-', '-']) {
            let end = find(&chars, i + 4, &['-', '-', '>']).map_or(chars.len(), |e| e + 3);
            line += chars[i..end].iter().filter(|x| **x == '\n').count();
            i = end;
            line_start = false;
            continue;
        }
        // A reference definition: `[label]: target` at the start of a line.
        if line_start && c == '[' {
            if let Some(close) = chars[i..].iter().position(|x| *x == ']' || *x == '\n') {
                let close = i + close;
                if chars[close] == ']' && chars.get(close + 1) == Some(&':') {
                    let rest: String = chars[close + 2..]
                        .iter()
                        .take_while(|x| **x != '\n')
                        .collect();
                    if let Some(target) = rest.split_whitespace().next() {
                        found.push((line, target.to_owned()));
                    }
                }
            }
        }
        if !c.is_whitespace() {
            line_start = false;
        }
        // An inline link or image: `](target)`.
        if c == ']' && chars.get(i + 1) == Some(&'(') {
            let mut depth = 0;
            let mut j = i + 2;
            while j < chars.len() && chars[j] != '\n' {
                match chars[j] {
                    '(' => depth += 1,
                    ')' if depth == 0 => break,
                    ')' => depth -= 1,
                    _ => {}
                }
                j += 1;
            }
            if chars.get(j) == Some(&')') {
                let inside: String = chars[i + 2..j].iter().collect();
                // `(target "title")`: the target is the first word.
                if let Some(target) = inside.split_whitespace().next() {
                    found.push((line, target.to_owned()));
                }
                i = j + 1;
                continue;
            }
        }
        i += 1;
    }
    found
}

/// The index just past the run of exactly `run` backticks that closes a code span opened
/// before `from`, if one comes before a blank line.
fn closing_backticks(chars: &[char], from: usize, run: usize) -> Option<usize> {
    let mut i = from;
    while i < chars.len() {
        if chars[i] == '\n' && chars.get(i + 1) == Some(&'\n') {
            return None;
        }
        if chars[i] == '`' {
            let len = chars[i..].iter().take_while(|x| **x == '`').count();
            if len == run {
                return Some(i + len);
            }
            i += len;
        } else {
            i += 1;
        }
    }
    None
}

fn find(chars: &[char], from: usize, needle: &[char]) -> Option<usize> {
    (from..chars.len()).find(|&i| chars[i..].starts_with(needle))
}

/// The anchors GitHub gives the headings of a Markdown page (ATX `#` and setext headings,
/// outside code), plus explicit `<a id="…">` / `<a name="…">` anchors.
fn anchors(text: &str) -> Vec<String> {
    let lines = prose_lines(text);
    let mut headings = Vec::new();
    for (n, line) in lines.iter().enumerate() {
        let trimmed = line.trim_start();
        let hashes = trimmed.chars().take_while(|c| *c == '#').count();
        if (1..=6).contains(&hashes)
            && line.len() - trimmed.len() < 4
            && trimmed[hashes..]
                .chars()
                .next()
                .is_none_or(char::is_whitespace)
        {
            let title = trimmed[hashes..].trim();
            let title = title.trim_end_matches('#').trim_end();
            headings.push(title.to_owned());
            continue;
        }
        let underline = line.trim();
        let is_underline = !underline.is_empty()
            && (underline.chars().all(|c| c == '=') || underline.chars().all(|c| c == '-'));
        if is_underline && n > 0 {
            let above = lines[n - 1].trim();
            let above_is_text = !above.is_empty()
                && !above.starts_with('#')
                && !above.starts_with('|')
                && !above.starts_with('-')
                && !above.starts_with('*')
                && !above.starts_with('>');
            if above_is_text {
                headings.push(above.to_owned());
            }
        }
    }
    let mut seen: HashMap<String, usize> = HashMap::new();
    let mut anchors = Vec::new();
    for heading in headings {
        let base = slug(&strip_inline_links(&heading));
        let count = seen.entry(base.clone()).or_insert(0);
        anchors.push(if *count == 0 {
            base.clone()
        } else {
            format!("{base}-{count}")
        });
        *count += 1;
    }
    for line in &lines {
        for key in ["id=\"", "name=\""] {
            let mut rest = *line;
            while let Some(at) = rest.find("<a ") {
                rest = &rest[at + 3..];
                let tag = rest.split('>').next().unwrap_or("");
                if let Some(start) = tag.find(key) {
                    let value = &tag[start + key.len()..];
                    if let Some(end) = value.find('"') {
                        anchors.push(value[..end].to_owned());
                    }
                }
            }
        }
    }
    anchors
}

/// `[text](target)` → `text`, as GitHub takes a heading's rendered text.
fn strip_inline_links(heading: &str) -> String {
    let mut out = String::new();
    let mut rest = heading;
    while let Some(open) = rest.find("](") {
        let Some(close) = rest[open..].find(')') else {
            break;
        };
        out.push_str(&rest[..open]);
        rest = &rest[open + close + 1..];
    }
    out.push_str(rest);
    out.replace("![", "").replace('[', "")
}

/// GitHub's anchor for a heading: lowercase; letters, digits, `-` and `_` kept; spaces → `-`;
/// everything else dropped.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            '-' | '_' => Some(c),
            c if c.is_alphanumeric() => Some(c),
            _ => None,
        })
        .collect()
}
