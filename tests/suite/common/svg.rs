//! A minimal check of the SVG files the CLI writes.

/// Element names of `svg` balance (a minimal well-formedness check: every start tag is
/// closed in order, attributes quoted, nothing after the root).
pub fn assert_well_formed_svg(svg: &str) {
    let mut stack: Vec<String> = Vec::new();
    let mut rest = svg.trim();
    assert!(rest.starts_with("<svg"), "{}", &rest[..rest.len().min(80)]);
    let mut closed_root = false;
    while let Some(i) = rest.find('<') {
        assert!(!closed_root || rest[..i].trim().is_empty(), "content after the root element");
        let j = rest[i..].find('>').expect("unterminated tag") + i;
        let tag = &rest[i + 1..j];
        assert_eq!(tag.matches('"').count() % 2, 0, "unbalanced quotes in <{tag}>");
        if let Some(name) = tag.strip_prefix('/') {
            assert_eq!(stack.pop().as_deref(), Some(name.trim()), "mismatched </{name}>");
            closed_root = stack.is_empty();
        } else if !tag.starts_with('?') && !tag.starts_with('!') && !tag.ends_with('/') {
            stack.push(tag.split_whitespace().next().unwrap().to_string());
        }
        rest = &rest[j + 1..];
    }
    assert!(stack.is_empty() && closed_root, "unclosed: {stack:?}");
}
