//! The candump log reader (`host_can::candump`), which reads logs a user hands to the replay
//! tools: any text, line by line (`parse_line`) and whole (`read_log`), gives frames or a
//! typed error, never a panic. A line that parses is a frame of this bus that `cansend_text`
//! and `CandumpWriter` write back into lines that parse to the same frame.
#![no_main]

use host_can::candump::{cansend_text, parse_line, read_log, CandumpWriter, LoggedFrame};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|input: &[u8]| {
    let text = String::from_utf8_lossy(input);
    let logged = read_log(&text);
    for line in text.lines() {
        let Ok((time_s, interface, frame)) = parse_line(line) else {
            continue;
        };
        assert!(
            time_s.is_finite() && time_s >= 0.0,
            "{line:?}: time {time_s}"
        );
        assert!(frame.id() <= protocol::MAX_STANDARD_ID, "{line:?}");
        let sent = format!("(0.000000) {interface} {}", cansend_text(&frame));
        assert_eq!(parse_line(&sent).map(|(_, _, f)| f), Ok(frame), "{sent:?}");
        // The writer takes the interface names canplayer reads back (1–15 bytes).
        if let Ok(mut writer) = CandumpWriter::new(Vec::new(), &interface) {
            writer
                .write(&LoggedFrame { time_s, frame })
                .expect("a parsed time is finite and not negative");
            let written = String::from_utf8(writer.finish().expect("a Vec")).expect("ASCII");
            let back = read_log(&written).expect("a written line reads back");
            assert_eq!(back.iter().map(|l| l.frame).collect::<Vec<_>>(), [frame]);
        }
    }
    if let Ok(frames) = logged {
        assert!(frames.len() <= text.lines().count());
    }
});
