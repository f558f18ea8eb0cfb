use proptest::prelude::*;

use super::*;

fn std_frame(id: u16, data: &[u8]) -> CanFrame {
    CanFrame::standard(id, data).unwrap()
}

#[test]
fn frames_are_written_like_socketcand() {
    let at = Duration::new(1_234_567_890, 123_456_789);
    assert_eq!(
        format_frame(&std_frame(0x123, &[0x11, 0x22, 0x33, 0x44]), at),
        "< frame 123 1234567890.123456 11223344 >"
    );
    let ext = CanFrame::extended(0x0200_FD01, &[0xAB]).unwrap();
    assert_eq!(
        format_frame(&ext, at),
        "< frame 0200FD01 1234567890.123456 AB >"
    );
    // Empty payload: two spaces, so python-can still finds three fields.
    assert_eq!(
        format_frame(&std_frame(0x7, &[]), Duration::from_millis(1500)),
        "< frame 007 1.500000  >"
    );
}

#[test]
fn python_can_send_lines_parse() {
    // python-can writes `{id:03X}`/`{id:08X}`, the DLC as `{:X}` and bytes as `{:x}`.
    assert_eq!(
        parse_command("< send 151 8 1 0 0 0 0 0 0 ff >"),
        Ok(Command::Send(std_frame(
            0x151,
            &[1, 0, 0, 0, 0, 0, 0, 0xFF]
        )))
    );
    assert_eq!(
        parse_command("< send 1AAAAAAA 2 1 F1 >"),
        Ok(Command::Send(
            CanFrame::extended(0x1AAA_AAAA, &[1, 0xF1]).unwrap()
        ))
    );
    // Eight digits make an extended id even when the value would fit 11 bits.
    assert_eq!(
        parse_command("< send 00000123 0 >"),
        Ok(Command::Send(CanFrame::extended(0x123, &[]).unwrap()))
    );
    assert_eq!(
        parse_command("< open can0 >"),
        Ok(Command::Open("can0".into()))
    );
    assert_eq!(parse_command("<rawmode>"), Ok(Command::RawMode));
    assert_eq!(parse_command("< echo >"), Ok(Command::Echo));
}

#[test]
fn malformed_commands_are_typed_errors() {
    let err = |text: &str| parse_command(text).unwrap_err();
    assert!(matches!(err("< fly >"), ParseError::Unknown { word } if word == "fly"));
    assert_eq!(err("< >"), ParseError::Empty);
    assert_eq!(err("send 1 0"), ParseError::NotAnElement);
    assert!(matches!(
        err("< send 123 2 11 >"),
        ParseError::BadDlc { bytes: 1, .. }
    ));
    assert!(matches!(
        err("< send 123 9 1 2 3 4 5 6 7 8 9 >"),
        ParseError::BadDlc { .. }
    ));
    assert!(matches!(
        err("< send 800 0 >"),
        ParseError::IdOutOfRange {
            extended: false,
            ..
        }
    ));
    assert!(matches!(
        err("< send 20000000 0 >"),
        ParseError::IdOutOfRange { extended: true, .. }
    ));
    assert!(matches!(
        err("< send 12G 0 >"),
        ParseError::BadHex {
            what: "identifier",
            ..
        }
    ));
    assert!(matches!(
        err("< send 123 1 100 >"),
        ParseError::BadHex {
            what: "data byte",
            ..
        }
    ));
    assert!(matches!(err("< send 123 >"), ParseError::FieldCount { .. }));
    assert!(matches!(
        err("< open >"),
        ParseError::FieldCount { word: "open", .. }
    ));
    assert!(matches!(
        err("< rawmode now >"),
        ParseError::FieldCount { .. }
    ));
}

#[test]
fn replies_parse_both_payload_layouts() {
    let expected = Reply::Frame {
        frame: std_frame(0x123, &[0x11, 0x22, 0x33, 0x44]),
        timestamp: Duration::new(23, 424_242_000),
    };
    assert_eq!(
        parse_reply("< frame 123 23.424242 11223344 >"),
        Ok(expected.clone())
    );
    assert_eq!(
        parse_reply("< frame 123 23.424242 11 22 33 44 >"),
        Ok(expected)
    );
    assert!(matches!(
        parse_reply("< frame 123 1.0  >"),
        Ok(Reply::Frame { frame, .. }) if frame.is_empty()
    ));
    assert!(parse_reply("< frame 123 1.0 112 >").is_err());
    assert!(parse_reply("< frame 123 x 11 >").is_err());
    assert_eq!(
        parse_reply("< error unknown command >"),
        Ok(Reply::Error("unknown command".into()))
    );
}

#[test]
fn framer_splits_joined_and_partial_elements() {
    let mut framer = Framer::default();
    framer.push(b"< hi >< ok >\n  < fra");
    assert_eq!(
        framer.next_element(),
        Some(Element::Complete("< hi >".into()))
    );
    assert_eq!(
        framer.next_element(),
        Some(Element::Complete("< ok >".into()))
    );
    assert_eq!(framer.next_element(), None);
    framer.push(b"me 123 1.0  >junk< echo >");
    assert_eq!(
        framer.next_element(),
        Some(Element::Complete("< frame 123 1.0  >".into()))
    );
    assert_eq!(framer.next_element(), Some(Element::Garbage("junk".into())));
    assert_eq!(
        framer.next_element(),
        Some(Element::Complete("< echo >".into()))
    );
    assert_eq!(framer.next_element(), None);
}

#[test]
fn framer_discards_overlong_elements_and_recovers() {
    let mut framer = Framer::default();
    let long = format!("< {} ", "x".repeat(MAX_ELEMENT_LEN));
    framer.push(long.as_bytes());
    assert!(matches!(framer.next_element(), Some(Element::Garbage(_))));
    assert_eq!(framer.next_element(), None);
    framer.push(b"more >< echo >");
    // The tail of the overlong element is junk outside an element.
    assert_eq!(
        framer.next_element(),
        Some(Element::Garbage("more >".into()))
    );
    assert_eq!(
        framer.next_element(),
        Some(Element::Complete("< echo >".into()))
    );
}

fn any_frame() -> impl Strategy<Value = CanFrame> {
    let id = prop_oneof![
        (0u16..=0x7FF).prop_map(CanId::Standard),
        (0u32..=0x1FFF_FFFF).prop_map(CanId::Extended),
    ];
    (id, proptest::collection::vec(any::<u8>(), 0..=8))
        .prop_map(|(id, data)| CanFrame::new(id, &data).unwrap())
}

proptest! {
    #[test]
    fn send_round_trips(frame in any_frame()) {
        let text = format_send(&frame);
        prop_assert_eq!(parse_command(&text), Ok(Command::Send(frame)));
    }

    #[test]
    fn frame_round_trips_to_the_microsecond(
        frame in any_frame(),
        secs in 0u64..4_000_000_000,
        micros in 0u32..1_000_000,
    ) {
        let timestamp = Duration::new(secs, micros * 1000);
        let text = format_frame(&frame, timestamp);
        prop_assert_eq!(parse_reply(&text), Ok(Reply::Frame { frame, timestamp }));
    }

    #[test]
    fn framer_reassembles_any_split(frames in proptest::collection::vec(any_frame(), 1..10), cut in any::<prop::sample::Index>()) {
        let text: String = frames.iter().map(format_send).collect();
        let cut = cut.index(text.len() + 1);
        let mut framer = Framer::default();
        framer.push(&text.as_bytes()[..cut]);
        let mut got = Vec::new();
        while let Some(element) = framer.next_element() {
            got.push(element);
        }
        framer.push(&text.as_bytes()[cut..]);
        while let Some(element) = framer.next_element() {
            got.push(element);
        }
        let parsed: Vec<Command> = got
            .iter()
            .map(|e| match e {
                Element::Complete(s) => parse_command(s).unwrap(),
                Element::Garbage(g) => panic!("garbage {g:?}"),
            })
            .collect();
        let expected: Vec<Command> = frames.into_iter().map(Command::Send).collect();
        prop_assert_eq!(parsed, expected);
    }

    #[test]
    fn parsers_never_panic(
        bytes in proptest::collection::vec(
            prop_oneof![
                prop::sample::select(b"<> \n.sendframeokhierror0123456789ABCDEFxz".to_vec()),
                any::<u8>(),
            ],
            0..120,
        ),
    ) {
        let text = String::from_utf8_lossy(&bytes);
        let _ = parse_command(&text);
        let _ = parse_reply(&text);
        let mut framer = Framer::default();
        framer.push(&bytes);
        while let Some(element) = framer.next_element() {
            if let Element::Complete(e) = element {
                let _ = parse_command(&e);
            }
        }
    }
}

/// An error's text reaches the client whole and in ASCII: its quotes kept, brackets that
/// would end the element early and bytes an ASCII reader fails on replaced (before, `<` and
/// `>` were dropped: `send  open NAME  first`).
#[test]
fn error_texts_keep_their_quoting_and_stay_ascii() {
    let text = format_reply(&Reply::Error(
        "no bus open: send `open NAME` first; junk \"<x\u{1b}é…>\"".into(),
    ));
    assert!(text.is_ascii(), "{text}");
    assert_eq!(text.matches('<').count(), 1, "{text}");
    assert_eq!(text.matches('>').count(), 1, "{text}");
    assert_eq!(
        parse_reply(&text),
        Ok(Reply::Error(
            "no bus open: send `open NAME` first; junk \"[x \\u{e9}...]\"".into()
        ))
    );
    for element in ["send 1 0", "< fly\u{1b}é >", "< send 12345 1 00 >"] {
        let error = parse_command(element).unwrap_err();
        let text = format_reply(&Reply::Error(error.to_string()));
        assert!(text.is_ascii() && text.matches('>').count() == 1, "{text}");
    }
}

/// socketcand's newer CAN FD elements have no form here (python-can reads neither): `fdsend`
/// is an unknown command, and a `< fdframe … >` from a server is not a frame.
#[test]
fn the_can_fd_elements_of_newer_socketcand_are_not_understood() {
    let error = parse_command("< fdsend 123 01 3 AA BB CC >").unwrap_err();
    assert_eq!(
        error,
        ParseError::Unknown {
            word: "fdsend".into()
        }
    );
    assert_eq!(error.to_string(), "unknown command `fdsend`");
    assert!(matches!(
        parse_reply("< fdframe 123 01 1.000000 AABBCC >"),
        Err(ParseError::Unknown { word }) if word == "fdframe"
    ));
    // A 12-byte payload in a classic element is refused, not read as CAN FD.
    assert!(matches!(
        parse_reply("< frame 123 1.000000 000102030405060708090A0B >"),
        Err(ParseError::BadHex { .. })
    ));
}
