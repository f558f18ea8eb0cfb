//! The fixture reader: the grammar on small texts (including every kind of malformed line) and
//! the repository's real fixture files.

use bus::candump::LineError;
use bus::fixtures::{self, FieldError, FixtureError, Location, SyntaxError};

/// The syntax error and its line, or a panic naming what came back instead.
fn syntax_error(text: &str) -> (usize, SyntaxError) {
    match fixtures::parse("t.log", text) {
        Err(FixtureError::Syntax { at, error }) => {
            assert_eq!(at.file, "t.log");
            (at.line, error)
        }
        other => panic!("expected a syntax error, got {other:?}"),
    }
}

#[test]
fn both_annotation_forms_blocks_and_shared_frames() {
    let text = "\
## prose, ignored
# 4AF firmware_reply_part: reply=1 part=11
# 4AF firmware_reply: reply=1 software=S-V1.8-8
(1700000000.013000) can0 4AF#0000000000000000

## exchange connect: two frames
# name=ping dir=h2m host=0xFD motor=0x7F
(0.001000) vcan0 0000FD7F#0000000000000000
";
    let v = fixtures::parse("t.log", text).unwrap();
    assert_eq!(v.len(), 3);
    assert_eq!(v[0].name, "firmware_reply_part");
    assert_eq!(v[0].id, Some(0x4AF));
    assert_eq!(
        v[0].at,
        Location {
            file: "t.log".into(),
            line: 2
        }
    );
    assert_eq!((v[1].at.line, v[1].frame_line), (3, 4));
    assert_eq!(v[0].frame, v[1].frame);
    assert_eq!(v[1].text("software"), Ok("S-V1.8-8"));
    assert_eq!(v[1].block, None);
    assert_eq!(v[2].name, "ping");
    assert_eq!(v[2].id, None);
    assert!(
        !v[2].has("name"),
        "the name is not repeated among the fields"
    );
    assert_eq!(v[2].int("host"), Ok(0xFD));
    assert_eq!(v[2].block.as_deref(), Some("connect"));
    assert!(v[2].frame.is_extended());
    assert_eq!(v[2].iface, "vcan0");
    assert_eq!(v[2].to_string(), "t.log:7 ping (0000FD7F#0000000000000000)");
}

#[test]
fn field_accessors_report_typed_errors() {
    let text = "# 2A5 joints_12: j1_mdeg=-90000 j2_mdeg=0x10 kp=10.5 mode=r expect=bad_dlc\n\
                (1.000000) can0 2A5#00\n";
    let v = &fixtures::parse("t.log", text).unwrap()[0];
    assert_eq!(v.int("j1_mdeg"), Ok(-90_000));
    assert_eq!(v.int("j2_mdeg"), Ok(16));
    assert_eq!(v.float("kp"), Ok(10.5));
    assert_eq!(v.float("j1_mdeg"), Ok(-90_000.0));
    assert_eq!(v.expect(), Some("bad_dlc"));
    assert!(matches!(v.int("kp"), Err(FieldError::NotInteger { .. })));
    assert!(matches!(v.float("mode"), Err(FieldError::NotNumber { .. })));
    let missing = v.int("j3_mdeg").unwrap_err();
    assert!(matches!(missing, FieldError::Missing { .. }));
    assert_eq!(
        missing.to_string(),
        "t.log:1 (joints_12): no field \"j3_mdeg\""
    );
}

#[test]
fn every_malformed_line_is_a_typed_error_with_its_line() {
    let frame = "(1.000000) can0 2A5#00\n";
    let cases: Vec<(String, usize, SyntaxError)> = vec![
        (frame.to_string(), 1, SyntaxError::Unannotated),
        ("## x\n# 2A5 j: a=1\n".into(), 2, SyntaxError::Dangling),
        (format!("#\n{frame}"), 1, SyntaxError::EmptyAnnotation),
        (
            format!("# 2A5 j a=1\n{frame}"),
            1,
            SyntaxError::UnknownAnnotation("2A5 j a=1".into()),
        ),
        (
            format!("# 2G5 j: a=1\n{frame}"),
            1,
            SyntaxError::BadId("2G5".into()),
        ),
        (format!("# 2A5: a=1\n{frame}"), 1, SyntaxError::MissingName),
        (
            format!("# 2A5 j k: a=1\n{frame}"),
            1,
            SyntaxError::MissingName,
        ),
        (
            format!("# 2A5 j: a=1 b\n{frame}"),
            1,
            SyntaxError::NotKeyValue("b".into()),
        ),
        (
            format!("# 2A5 j: a=\n{frame}"),
            1,
            SyntaxError::NotKeyValue("a=".into()),
        ),
        (
            format!("# 2A5 j: a=1 a=2\n{frame}"),
            1,
            SyntaxError::DuplicateKey("a".into()),
        ),
        (
            format!("# dir=h2m type=0\n{frame}"),
            1,
            SyntaxError::MissingName,
        ),
        (
            format!("## x\n# 2A6 j: a=1\n{frame}"),
            2,
            SyntaxError::IdMismatch {
                annotated: 0x2A6,
                frame: 0x2A5,
            },
        ),
        (
            "# 2A5 j: a=1\n(1.000000) can0 2A5#0\n".into(),
            2,
            SyntaxError::Candump(LineError::BadData("0".into())),
        ),
        (
            "# 2A5 j: a=1\nhello\n".into(),
            2,
            SyntaxError::Candump(LineError::BadTimestamp),
        ),
        (
            format!("# 2A5 j: a=1\n## exchange b: x\n{frame}"),
            1,
            SyntaxError::Dangling,
        ),
        (
            format!("## exchange : x\n# 2A5 j: a=1\n{frame}"),
            1,
            SyntaxError::BadBlock("## exchange : x".into()),
        ),
    ];
    for (text, line, error) in cases {
        assert_eq!(syntax_error(&text), (line, error), "{text:?}");
    }
    let shown = fixtures::parse("mit.log", "# 2A5 j: a=1 b\n(1.0) can0 2A5#\n")
        .unwrap_err()
        .to_string();
    assert_eq!(shown, "mit.log:1: \"b\" is not key=value");
}

#[test]
fn missing_and_empty_files_are_errors() {
    let missing = fixtures::read_file(fixtures::repo_path("piper/no_such_file.log"));
    assert!(
        matches!(missing, Err(FixtureError::Io { .. })),
        "{missing:?}"
    );
    let dir = std::env::temp_dir().join(format!("armhil-fixtures-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    assert!(matches!(
        fixtures::read_dir(&dir),
        Err(FixtureError::Empty { .. })
    ));
    let prose_only = dir.join("prose.log");
    std::fs::write(&prose_only, "## nothing but prose\n").unwrap();
    assert!(matches!(
        fixtures::read_file(&prose_only),
        Err(FixtureError::Empty { .. })
    ));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_repository_fixtures_follow_the_grammar() {
    let piper = fixtures::read_dir(fixtures::repo_path("piper")).unwrap();
    let robstride = fixtures::read_dir(fixtures::repo_path("robstride")).unwrap();
    assert!(piper.len() > 300, "{} Piper vectors", piper.len());
    assert!(
        robstride.len() > 30,
        "{} RobStride vectors",
        robstride.len()
    );
    // Piper annotations name their identifier; RobStride ones use the name= form.
    assert!(piper
        .iter()
        .all(|v| v.id.is_some() && !v.frame.is_extended()));
    assert!(robstride
        .iter()
        .all(|v| v.id.is_none() && v.frame.is_extended()));
    let blocks: std::collections::BTreeSet<_> =
        piper.iter().filter_map(|v| v.block.as_deref()).collect();
    assert!(blocks.len() >= 10, "{blocks:?}");
}
