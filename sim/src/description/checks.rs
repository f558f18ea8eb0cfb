//! What urdf-rs accepts but the physics cannot run, caught before it is parsed, each named
//! by its line: nesting too deep to parse safely, names given twice, limits the wrong way
//! round, numbers that are not finite, inertias no body has.

use nalgebra::Matrix3;

use super::DescriptionError;

/// Deepest element nesting read. URDFs nest five or six deep (`robot/link/collision/
/// geometry/mesh`), plugin blocks a few more; urdf-rs recurses per level and a hostile
/// file 100,000 deep overflows the stack.
pub const MAX_XML_DEPTH: usize = 64;
/// Most elements read. The largest public robot description has about 3,000; 5,000 links
/// with their inertials, visuals and joints are ~60,000.
pub const MAX_XML_ELEMENTS: usize = 500_000;

/// Checks URDF text; the first problem found, at its line.
pub fn check_urdf_text(text: &str) -> Result<roxmltree::Document<'_>, DescriptionError> {
    check_depth(text)?;
    let options = roxmltree::ParsingOptions {
        allow_dtd: false,
        nodes_limit: u32::try_from(MAX_XML_ELEMENTS * 2).unwrap_or(u32::MAX),
    };
    let doc = roxmltree::Document::parse_with_options(text, options).map_err(|e| {
        DescriptionError::at(
            Some(e.pos().row as usize),
            format!("not well-formed XML: {e}"),
        )
    })?;
    let lines = Lines::of(text);
    let root = doc.root_element();
    if root.tag_name().name() != "robot" {
        return Err(DescriptionError::at(
            Some(line_of(&lines, root)),
            format!(
                "the root element is <{}>, not <robot>",
                root.tag_name().name()
            ),
        ));
    }
    check_names(&lines, root, "link")?;
    check_names(&lines, root, "joint")?;
    for node in root.children().filter(|n| n.is_element()) {
        match node.tag_name().name() {
            "link" => check_link(&lines, node)?,
            "joint" => check_joint(&lines, node)?,
            _ => {}
        }
    }
    Ok(doc)
}

/// Where each line of the text starts, to name a node's line without rescanning the text
/// (roxmltree's own `text_pos_at` counts from the start at every call: quadratic over a
/// 5,000-link file).
pub(super) struct Lines {
    newlines: Vec<usize>,
}

impl Lines {
    fn of(text: &str) -> Self {
        Self {
            newlines: text
                .bytes()
                .enumerate()
                .filter(|(_, b)| *b == b'\n')
                .map(|(i, _)| i)
                .collect(),
        }
    }
}

/// 1-based line of `node` in the text.
pub(super) fn line_of(doc: &Lines, node: roxmltree::Node<'_, '_>) -> usize {
    doc.newlines.partition_point(|&n| n < node.range().start) + 1
}

/// Nesting depth of the text, counted without building a tree: tags, skipping comments,
/// CDATA, processing instructions and quoted attribute values.
fn check_depth(text: &str) -> Result<(), DescriptionError> {
    let bytes = text.as_bytes();
    let (mut depth, mut line, mut i) = (0usize, 1usize, 0usize);
    let skip_to = |from: usize, end: &[u8]| {
        bytes[from..]
            .windows(end.len())
            .position(|w| w == end)
            .map_or(bytes.len(), |p| from + p + end.len())
    };
    while i < bytes.len() {
        match bytes[i] {
            b'\n' => line += 1,
            b'<' => {
                let rest = &bytes[i..];
                let end = if rest.starts_with(b"<!--") {
                    skip_to(i, b"-->")
                } else if rest.starts_with(b"<![CDATA[") {
                    skip_to(i, b"]]>")
                } else if rest.starts_with(b"<?") {
                    skip_to(i, b"?>")
                } else if rest.starts_with(b"<!") {
                    skip_to(i, b">")
                } else {
                    // A tag: find its `>` outside quotes.
                    let mut j = i + 1;
                    let mut quote = None;
                    while j < bytes.len() {
                        match (quote, bytes[j]) {
                            (None, b'"' | b'\'') => quote = Some(bytes[j]),
                            (Some(q), c) if c == q => quote = None,
                            (None, b'>') => break,
                            _ => {}
                        }
                        j += 1;
                    }
                    if rest.get(1) == Some(&b'/') {
                        depth = depth.saturating_sub(1);
                    } else if bytes.get(j.wrapping_sub(1)) != Some(&b'/') {
                        depth += 1;
                        if depth > MAX_XML_DEPTH {
                            return Err(DescriptionError::at(
                                Some(line),
                                format!("elements nest more than {MAX_XML_DEPTH} deep"),
                            ));
                        }
                    }
                    j + 1
                };
                line += bytes[i..end.min(bytes.len())]
                    .iter()
                    .filter(|&&b| b == b'\n')
                    .count();
                i = end;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    Ok(())
}

fn check_names(
    doc: &Lines,
    root: roxmltree::Node<'_, '_>,
    tag: &str,
) -> Result<(), DescriptionError> {
    let mut seen = std::collections::HashMap::new();
    for node in root.children().filter(|n| n.has_tag_name(tag)) {
        let line = line_of(doc, node);
        let Some(name) = node.attribute("name").filter(|n| !n.is_empty()) else {
            return Err(DescriptionError::at(
                Some(line),
                format!("a <{tag}> without a name"),
            ));
        };
        if let Some(first) = seen.insert(name, line) {
            return Err(DescriptionError::at(
                Some(line),
                format!("two <{tag}>s are called `{name}` (the first on line {first})"),
            ));
        }
    }
    Ok(())
}

/// The numbers of attribute `attr` of `node`, which must be `count` finite numbers.
fn numbers(
    doc: &Lines,
    node: roxmltree::Node<'_, '_>,
    attr: &str,
    count: usize,
) -> Result<Option<Vec<f64>>, DescriptionError> {
    let Some(text) = node.attribute(attr) else {
        return Ok(None);
    };
    let values: Vec<f64> = text
        .split_whitespace()
        .map(|v| v.parse::<f64>().unwrap_or(f64::NAN))
        .collect();
    if values.len() != count || values.iter().any(|v| !v.is_finite()) {
        let what = if count == 1 {
            "a finite number".to_owned()
        } else {
            format!("{count} finite numbers")
        };
        return Err(DescriptionError::at(
            Some(line_of(doc, node)),
            format!(
                "<{} {attr}=\"{}\"> must be {what}",
                node.tag_name().name(),
                crate::yaml_words::elide_long_tokens(text)
            ),
        ));
    }
    Ok(Some(values))
}

fn check_origins(doc: &Lines, node: roxmltree::Node<'_, '_>) -> Result<(), DescriptionError> {
    for origin in node.descendants().filter(|n| n.has_tag_name("origin")) {
        numbers(doc, origin, "xyz", 3)?;
        numbers(doc, origin, "rpy", 3)?;
    }
    Ok(())
}

fn check_link(doc: &Lines, link: roxmltree::Node<'_, '_>) -> Result<(), DescriptionError> {
    check_origins(doc, link)?;
    for scale in link.descendants().filter(|n| n.has_tag_name("mesh")) {
        numbers(doc, scale, "scale", 3)?;
    }
    let Some(inertial) = link.children().find(|n| n.has_tag_name("inertial")) else {
        return Ok(());
    };
    let name = link.attribute("name").unwrap_or_default();
    if let Some(mass) = inertial.children().find(|n| n.has_tag_name("mass")) {
        if let Some(m) = numbers(doc, mass, "value", 1)? {
            if m[0] < 0.0 {
                return Err(DescriptionError::at(
                    Some(line_of(doc, mass)),
                    format!("link `{name}` has a negative mass ({} kg)", m[0]),
                ));
            }
        }
    }
    let Some(inertia) = inertial.children().find(|n| n.has_tag_name("inertia")) else {
        return Ok(());
    };
    let mut v = [0.0; 6];
    for (slot, attr) in v.iter_mut().zip(["ixx", "ixy", "ixz", "iyy", "iyz", "izz"]) {
        *slot = numbers(doc, inertia, attr, 1)?.map_or(0.0, |n| n[0]);
    }
    let [ixx, ixy, ixz, iyy, iyz, izz] = v;
    let tensor = Matrix3::new(ixx, ixy, ixz, ixy, iyy, iyz, ixz, iyz, izz);
    let eigen = tensor.symmetric_eigenvalues();
    // Exported inertias carry round-off: a tolerance of a millionth of the largest moment,
    // and 1e-7 kg·m² however small the part (a published 1 mg antenna has a principal moment
    // of -4e-8 kg·m², which no simulation can tell from zero).
    let scale = eigen.iter().fold(0.0f64, |m, e| m.max(e.abs()));
    let tolerance = 1e-6 * scale + 1e-7;
    if let Some(low) = eigen.iter().copied().find(|e| *e < -tolerance) {
        return Err(DescriptionError::at(
            Some(line_of(doc, inertia)),
            format!(
                "link `{name}`'s inertia is not positive semi-definite (a principal moment of {low:.3e} kg·m²); no body has it"
            ),
        ));
    }
    Ok(())
}

fn check_joint(doc: &Lines, joint: roxmltree::Node<'_, '_>) -> Result<(), DescriptionError> {
    check_origins(doc, joint)?;
    let name = joint.attribute("name").unwrap_or_default();
    let kind = joint.attribute("type").unwrap_or_default();
    let line = line_of(doc, joint);
    if let Some(axis) = joint.children().find(|n| n.has_tag_name("axis")) {
        if let Some(a) = numbers(doc, axis, "xyz", 3)? {
            let movable = matches!(kind, "revolute" | "continuous" | "prismatic");
            if movable && a.iter().all(|c| *c == 0.0) {
                return Err(DescriptionError::at(
                    Some(line_of(doc, axis)),
                    format!("joint `{name}`'s axis is zero"),
                ));
            }
        }
    }
    if let Some(limit) = joint.children().find(|n| n.has_tag_name("limit")) {
        let lower = numbers(doc, limit, "lower", 1)?.map(|v| v[0]);
        let upper = numbers(doc, limit, "upper", 1)?.map(|v| v[0]);
        for attr in ["effort", "velocity"] {
            if let Some(v) = numbers(doc, limit, attr, 1)? {
                if v[0] < 0.0 {
                    return Err(DescriptionError::at(
                        Some(line_of(doc, limit)),
                        format!("joint `{name}`'s {attr} limit is negative ({})", v[0]),
                    ));
                }
            }
        }
        let (lower, upper) = (lower.unwrap_or(0.0), upper.unwrap_or(0.0));
        if matches!(kind, "revolute" | "prismatic") && lower > upper {
            return Err(DescriptionError::at(
                Some(line_of(doc, limit)),
                format!("joint `{name}`'s limits are the wrong way round (lower {lower} > upper {upper})"),
            ));
        }
    } else if matches!(kind, "revolute" | "prismatic") {
        return Err(DescriptionError::at(
            Some(line),
            format!("{kind} joint `{name}` has no <limit> (URDF requires one)"),
        ));
    }
    if let Some(mimic) = joint.children().find(|n| n.has_tag_name("mimic")) {
        numbers(doc, mimic, "multiplier", 1)?;
        numbers(doc, mimic, "offset", 1)?;
    }
    if let Some(dynamics) = joint.children().find(|n| n.has_tag_name("dynamics")) {
        for attr in ["damping", "friction"] {
            if let Some(v) = numbers(doc, dynamics, attr, 1)? {
                if v[0] < 0.0 {
                    return Err(DescriptionError::at(
                        Some(line_of(doc, dynamics)),
                        format!("joint `{name}`'s {attr} is negative ({})", v[0]),
                    ));
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn robot(body: &str) -> String {
        format!("<?xml version=\"1.0\"?>\n<robot name=\"r\">\n{body}\n</robot>\n")
    }

    fn link(name: &str) -> String {
        format!("<link name=\"{name}\"><inertial><mass value=\"1\"/><inertia ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" izz=\"0.01\"/></inertial></link>")
    }

    fn error(text: &str) -> String {
        check_urdf_text(text).map(|_| ()).unwrap_err().to_string()
    }

    #[test]
    fn a_good_urdf_passes() {
        let text = robot(&format!(
            "{}\n{}\n<joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>",
            link("a"),
            link("b")
        ));
        check_urdf_text(&text).unwrap();
    }

    #[test]
    fn limits_the_wrong_way_round_or_not_finite_are_refused_at_their_line() {
        let joint = |limit: &str| {
            robot(&format!(
                "{}\n{}\n<joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/>\n<limit {limit} effort=\"1\" velocity=\"1\"/></joint>",
                link("a"),
                link("b")
            ))
        };
        let e = error(&joint("lower=\"1\" upper=\"-1\""));
        assert!(
            e.starts_with("line 6: joint `j`'s limits are the wrong way round"),
            "{e}"
        );
        let e = error(&joint("lower=\"nan\" upper=\"1\""));
        assert!(
            e.contains("line 6: <limit lower=\"nan\"> must be a finite number"),
            "{e}"
        );
        let e = error(&joint("lower=\"-inf\" upper=\"1\""));
        assert!(e.contains("must be a finite number"), "{e}");
    }

    #[test]
    fn non_finite_origins_and_axes_and_zero_axes_are_refused() {
        let joint = |extra: &str| {
            robot(&format!(
                "{}\n{}\n<joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/>{extra}<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>",
                link("a"),
                link("b")
            ))
        };
        assert!(error(&joint("<origin xyz=\"0 NaN 0\"/>"))
            .contains("<origin xyz=\"0 NaN 0\"> must be 3 finite numbers"));
        assert!(error(&joint("<origin rpy=\"0 0\"/>")).contains("must be 3 finite numbers"));
        assert!(error(&joint("<axis xyz=\"inf 0 0\"/>")).contains("<axis xyz"));
        assert!(error(&joint("<axis xyz=\"0 0 0\"/>")).contains("joint `j`'s axis is zero"));
    }

    #[test]
    fn inertias_no_body_has_are_refused() {
        let text = robot("<link name=\"a\">\n<inertial><mass value=\"-2\"/></inertial></link>");
        assert!(error(&text).starts_with("line 4: link `a` has a negative mass"));
        let text = robot("<link name=\"a\"><inertial><mass value=\"1\"/>\n<inertia ixx=\"-0.1\" ixy=\"0\" ixz=\"0\" iyy=\"0.1\" iyz=\"0\" izz=\"0.1\"/></inertial></link>");
        let e = error(&text);
        assert!(
            e.starts_with("line 4: link `a`'s inertia is not positive semi-definite"),
            "{e}"
        );
        // Positive diagonal, but a product of inertia larger than the moments: still no body.
        let text = robot("<link name=\"a\"><inertial><mass value=\"1\"/><inertia ixx=\"0.1\" ixy=\"0.5\" ixz=\"0\" iyy=\"0.1\" iyz=\"0\" izz=\"0.1\"/></inertial></link>");
        assert!(error(&text).contains("not positive semi-definite"));
        // Round-off on a milligram part is not refused.
        let text = robot("<link name=\"a\"><inertial><mass value=\"1e-6\"/><inertia ixx=\"2.4e-8\" ixy=\"6.1e-8\" ixz=\"0\" iyy=\"2.4e-8\" iyz=\"0\" izz=\"1e-8\"/></inertial></link>");
        check_urdf_text(&text).unwrap();
    }

    #[test]
    fn a_texture_without_a_file_is_taken_as_ros_takes_it() {
        let text = robot(&format!(
            "{}\n<material name=\"m\"><color rgba=\"1 0 0 1\"/><texture/></material>",
            link("a")
        ));
        let description = crate::description::Description::parse(text, Default::default()).unwrap();
        assert_eq!(description.robot().links.len(), 1);
    }

    #[test]
    fn two_links_or_joints_with_one_name_are_refused() {
        let text = robot(&format!("{}\n{}", link("a"), link("a")));
        assert_eq!(
            error(&text),
            "line 4: two <link>s are called `a` (the first on line 3)"
        );
    }

    #[test]
    fn deep_nesting_is_refused_without_recursing() {
        let deep = format!(
            "<robot name=\"r\"><link name=\"a\">{}{}</link></robot>",
            "<x>".repeat(100_000),
            "</x>".repeat(100_000)
        );
        assert!(error(&deep).contains("elements nest more than 64 deep"));
        // Quoted `>` and comments do not confuse the count.
        let fine = robot("<!-- <a><b><c> --><link name=\"a>b\"/>");
        check_urdf_text(&fine).unwrap();
    }

    #[test]
    fn not_a_robot_or_not_xml_is_refused() {
        assert!(error("<robots/>").contains("the root element is <robots>, not <robot>"));
        assert!(
            error("<robot>\n<link name=\"a\"></robot>").starts_with("line 2: not well-formed XML")
        );
    }
}
