//! The bus log in the can-utils log format (`candump -L`, `candump -l`), which `canplayer`
//! replays: one CAN FD frame per line, `(SECONDS.MICROSECONDS) IFACE ID##<flags><DATA>`.
//!
//! The format follows can-utils' `candump.c` (`sprint_timestamp`) and `lib.c`
//! (`snprintf_canframe`, `parse_canframe`): the timestamp is `(%010llu.%06llu)`; a standard id
//! is 3 upper-case hex digits; `##` marks CAN FD and is followed by one hex digit of the
//! `canfd_frame.flags` and the payload as upper-case hex without separators. candump (since
//! can-utils 2025.01) and the kernel (since CAN XL support) set `CANFD_FDF` (0x4) in the flags
//! of every CAN FD frame, so a frame sent without bit-rate switch is logged as `ID##4DATA`;
//! that is what this module writes ([`FD_FLAGS`]). `canplayer` accepts any flags digit.

use std::fmt::Write as _;
use std::io::{self, Write};

use protocol::{Frame, MAX_STANDARD_ID};

/// A frame seen on the bus, with when: one line of the log.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoggedFrame {
    /// When it was seen: simulation time in lockstep, wall time since start in real time, s.
    pub time_s: f64,
    /// The frame.
    pub frame: Frame,
}

/// The flags digit written after `##`: `CANFD_FDF` (0x4), without `CANFD_BRS` (0x1) or
/// `CANFD_ESI` (0x2), as candump logs a CAN FD frame sent without bit-rate switch.
pub const FD_FLAGS: u8 = 0x4;

/// The flags digit [`cansend_text`] writes: `CANFD_BRS` (0x1), a CAN FD frame sent with
/// bit-rate switch, as the robot's nodes send.
pub const CANSEND_FLAGS: u8 = 0x1;

/// Longest interface name Linux allows (`IFNAMSIZ` − 1), bytes.
const MAX_INTERFACE_LEN: usize = 15;

/// Writes [`LoggedFrame`]s as candump log lines, one `write` per frame, each line ending in
/// `\n`. Lines go straight to the inner writer: wrap a file in a [`io::BufWriter`].
#[derive(Debug)]
pub struct CandumpWriter<W: Write> {
    out: W,
    interface: String,
    line: String,
}

impl<W: Write> CandumpWriter<W> {
    /// A writer logging every frame as seen on `interface` (e.g. `vcan0`). Fails with
    /// [`io::ErrorKind::InvalidInput`] if `interface` is not a name canplayer can read back:
    /// empty, longer than 15 bytes, or containing whitespace.
    pub fn new(writer: W, interface: &str) -> io::Result<Self> {
        if interface.is_empty()
            || interface.len() > MAX_INTERFACE_LEN
            || interface.contains(char::is_whitespace)
        {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "`{interface}` is not a CAN interface name: it must be 1–15 bytes without \
                     whitespace"
                ),
            ));
        }
        Ok(CandumpWriter {
            out: writer,
            interface: interface.to_owned(),
            line: String::new(),
        })
    }

    /// Writes one line for `logged`, its time rounded to the microsecond. Fails with
    /// [`io::ErrorKind::InvalidInput`] (writing nothing) if the time is negative or not
    /// finite, else with the inner writer's error.
    pub fn write(&mut self, logged: &LoggedFrame) -> io::Result<()> {
        self.line.clear();
        format_line(
            &mut self.line,
            logged.time_s,
            &self.interface,
            &logged.frame,
        )?;
        self.out.write_all(self.line.as_bytes())
    }

    /// Flushes the inner writer (puts the lines written so far where it writes them).
    pub fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }

    /// Flushes the inner writer and returns it.
    pub fn finish(mut self) -> io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

fn format_line(line: &mut String, time_s: f64, interface: &str, frame: &Frame) -> io::Result<()> {
    let micros = micros(time_s).ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("cannot log a frame at {time_s} s: candump times are finite and not negative"),
        )
    })?;
    let (seconds, fraction) = (micros / 1_000_000, micros % 1_000_000);
    write!(line, "({seconds:010}.{fraction:06}) {interface} ").map_err(io::Error::other)?;
    push_frame(line, frame, FD_FLAGS);
    line.push('\n');
    Ok(())
}

/// Appends `frame` in can-utils' frame notation, `ID##<flags><DATA>`.
fn push_frame(line: &mut String, frame: &Frame, flags: u8) {
    const HEX: &[u8; 16] = b"0123456789ABCDEF";
    let id = frame.id();
    for shift in [8, 4, 0] {
        line.push(char::from(HEX[usize::from(id >> shift & 0xF)]));
    }
    line.push_str("##");
    line.push(char::from(HEX[usize::from(flags & 0xF)]));
    for byte in frame.data() {
        line.push(char::from(HEX[usize::from(byte >> 4)]));
        line.push(char::from(HEX[usize::from(byte & 0xF)]));
    }
}

/// `frame` as `cansend` takes it: `ID##<flags><DATA>` with the bit-rate-switch flag
/// ([`CANSEND_FLAGS`]), as the robot's nodes send their frames.
pub fn cansend_text(frame: &Frame) -> String {
    let mut text = String::with_capacity(6 + 2 * frame.data().len());
    push_frame(&mut text, frame, CANSEND_FLAGS);
    text
}

/// Why a log could not be read: the line (1-based) and its cause.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("line {line}: {cause}")]
pub struct CandumpLogError {
    /// The line number, from 1.
    pub line: usize,
    /// What is wrong with it.
    pub cause: CandumpParseError,
}

/// Every frame of a candump log's text, in order. A log still being written may end in half a
/// line: only complete lines (ending in `\n`) count, and blank lines are skipped. The first
/// line that is not a frame of this bus is the error.
pub fn read_log(text: &str) -> Result<Vec<LoggedFrame>, CandumpLogError> {
    let complete = text
        .rfind('\n')
        .map_or("", |end| text.get(..end).unwrap_or(""));
    complete
        .lines()
        .enumerate()
        .filter(|(_, line)| !line.trim().is_empty())
        .map(|(index, line)| {
            parse_line(line)
                .map(|(time_s, _, frame)| LoggedFrame { time_s, frame })
                .map_err(|cause| CandumpLogError {
                    line: index + 1,
                    cause,
                })
        })
        .collect()
}

/// `time_s` in whole microseconds, or `None` if negative or not finite.
fn micros(time_s: f64) -> Option<u64> {
    let micros = (time_s * 1e6).round();
    // The range check makes the cast exact (it saturates only at the top, beyond any log).
    (micros.is_finite() && micros >= 0.0).then_some(micros as u64)
}

/// Why a line is not a CAN FD frame in the candump log format.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum CandumpParseError {
    /// The line does not start with `(` … `)`.
    #[error("the line does not start with a `(seconds.fraction)` timestamp")]
    MissingTimestamp,
    /// The text between the parentheses is not `digits.digits`.
    #[error("`{text}` is not a `seconds.fraction` timestamp of decimal digits")]
    BadTimestamp {
        /// The text between the parentheses.
        text: String,
    },
    /// Nothing follows the timestamp.
    #[error("the line has no interface name after its timestamp")]
    MissingInterface,
    /// Nothing follows the interface name.
    #[error("the line has no frame after its interface name")]
    MissingFrame,
    /// The frame does not start with 3 or 8 hex digits and `#`.
    #[error("`{text}` does not start with a CAN id of 3 or 8 hex digits followed by `#`")]
    BadId {
        /// The frame text.
        text: String,
    },
    /// The frame has a 29-bit identifier (8 hex digits).
    #[error("`{text}` has a 29-bit id; the robot's bus uses 11-bit ids only")]
    ExtendedId {
        /// The frame text.
        text: String,
    },
    /// The 3-digit identifier is above 0x7FF.
    #[error("id 0x{id:03X} is above 0x7FF, the largest 11-bit id")]
    IdOutOfRange {
        /// The identifier.
        id: u16,
    },
    /// A classic CAN, remote or CAN XL frame: the id is not followed by `##`.
    #[error("`{text}` is not a CAN FD frame (`ID##<flags><data>`)")]
    NotCanFd {
        /// The frame text.
        text: String,
    },
    /// `##` is not followed by a hex flags digit.
    #[error("`{text}` has no hex flags digit after `##`")]
    BadFlags {
        /// The frame text.
        text: String,
    },
    /// The payload is not pairs of hex digits (optionally `.`-separated).
    #[error("`{text}` has a payload that is not pairs of hex digits")]
    BadData {
        /// The frame text.
        text: String,
    },
    /// The payload length is not a CAN FD data length.
    #[error("the payload has {len} bytes, not a CAN FD length (0–8, 12, 16, 20, 24, 32, 48, 64)")]
    BadLength {
        /// Payload bytes.
        len: usize,
    },
}

/// Reads one candump log line, as [`CandumpWriter`] or `candump -L` writes it, into (time in
/// seconds, interface name, frame). Accepts what can-utils' `parse_canframe` accepts for a CAN
/// FD frame with an 11-bit id: any flags digit (discarded), hex digits of either case, `.`
/// between bytes. Surrounding whitespace and anything after the frame (candump's `-x` extras)
/// are ignored. Classic CAN, remote, CAN XL and 29-bit frames are errors.
pub fn parse_line(line: &str) -> Result<(f64, String, Frame), CandumpParseError> {
    let rest = line
        .trim()
        .strip_prefix('(')
        .ok_or(CandumpParseError::MissingTimestamp)?;
    let (stamp, rest) = rest
        .split_once(')')
        .ok_or(CandumpParseError::MissingTimestamp)?;
    let time_s = parse_timestamp(stamp)?;
    let mut fields = rest.split_whitespace();
    let interface = fields.next().ok_or(CandumpParseError::MissingInterface)?;
    let frame = parse_frame(fields.next().ok_or(CandumpParseError::MissingFrame)?)?;
    Ok((time_s, interface.to_owned(), frame))
}

fn parse_timestamp(text: &str) -> Result<f64, CandumpParseError> {
    let bad = || CandumpParseError::BadTimestamp {
        text: text.to_owned(),
    };
    let digits = |part: &str| !part.is_empty() && part.bytes().all(|b| b.is_ascii_digit());
    match text.split_once('.') {
        Some((seconds, fraction)) if digits(seconds) && digits(fraction) => text
            .parse::<f64>()
            .ok()
            .filter(|time| time.is_finite())
            .ok_or_else(bad),
        _ => Err(bad()),
    }
}

fn parse_frame(text: &str) -> Result<Frame, CandumpParseError> {
    let owned = || text.to_owned();
    let bad_id = || CandumpParseError::BadId { text: owned() };
    let (id_text, rest) = text.split_once('#').ok_or_else(bad_id)?;
    if !id_text.bytes().all(|b| b.is_ascii_hexdigit()) {
        return Err(bad_id());
    }
    match id_text.len() {
        3 => {}
        8 => return Err(CandumpParseError::ExtendedId { text: owned() }),
        5 => return Err(CandumpParseError::NotCanFd { text: owned() }),
        _ => return Err(bad_id()),
    }
    let id = u16::from_str_radix(id_text, 16).map_err(|_| bad_id())?;
    let body = rest
        .strip_prefix('#')
        .ok_or_else(|| CandumpParseError::NotCanFd { text: owned() })?;
    let mut chars = body.chars();
    if !chars.next().is_some_and(|flags| flags.is_ascii_hexdigit()) {
        return Err(CandumpParseError::BadFlags { text: owned() });
    }
    let data =
        parse_hex(chars.as_str()).ok_or_else(|| CandumpParseError::BadData { text: owned() })?;
    if id > MAX_STANDARD_ID {
        return Err(CandumpParseError::IdOutOfRange { id });
    }
    Frame::new(id, &data).ok_or(CandumpParseError::BadLength { len: data.len() })
}

/// Bytes from pairs of hex digits, each pair optionally preceded by one `.`.
fn parse_hex(text: &str) -> Option<Vec<u8>> {
    let mut digits = text.chars().peekable();
    let mut data = Vec::with_capacity(text.len() / 2);
    loop {
        digits.next_if_eq(&'.');
        let Some(high) = digits.next() else {
            return Some(data);
        };
        let low = digits.next()?;
        data.push(u8::try_from(high.to_digit(16)? << 4 | low.to_digit(16)?).ok()?);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(id: u16, data: &[u8]) -> Frame {
        Frame::new(id, data).unwrap()
    }

    fn line(time_s: f64, interface: &str, frame: Frame) -> String {
        let mut writer = CandumpWriter::new(Vec::new(), interface).unwrap();
        writer.write(&LoggedFrame { time_s, frame }).unwrap();
        String::from_utf8(writer.finish().unwrap()).unwrap()
    }

    #[test]
    fn known_frame_is_written_as_candump_does() {
        let known = frame(0x101, &[0x01, 0xAB, 0xcd, 0x00]);
        assert_eq!(
            line(0.004, "vcan0", known),
            "(0000000000.004000) vcan0 101##401ABCD00\n"
        );
        assert_eq!(
            line(1_700_000_000.123456, "can0", frame(0x00A, &[])),
            "(1700000000.123456) can0 00A##4\n"
        );
    }

    #[test]
    fn time_is_rounded_to_the_microsecond() {
        assert!(line(2.999_999_6, "vcan0", frame(0x7FF, &[1])).starts_with("(0000000003.000000) "));
        assert!(line(-1e-7, "vcan0", frame(0x7FF, &[1])).starts_with("(0000000000.000000) "));
    }

    #[test]
    fn written_lines_parse_back_to_the_same_frames() {
        let payload: Vec<u8> = (0..64).map(|i| (i * 37 % 256) as u8).collect();
        let frames: Vec<LoggedFrame> = protocol::dlc::FD_LENGTHS
            .iter()
            .enumerate()
            .map(|(i, &len)| LoggedFrame {
                time_s: 0.004 * i as f64 + if i == 3 { 1_700_000_000.0 } else { 0.0 },
                frame: frame(0x7FF - i as u16 * 0x81, &payload[..len]),
            })
            .collect();
        let mut writer = CandumpWriter::new(Vec::new(), "vcan0").unwrap();
        for logged in &frames {
            writer.write(logged).unwrap();
        }
        let text = String::from_utf8(writer.finish().unwrap()).unwrap();
        assert_eq!(text.lines().count(), frames.len());
        for (text, logged) in text.lines().zip(&frames) {
            let (time_s, interface, frame) = parse_line(text).unwrap();
            let to_the_microsecond = (logged.time_s * 1e6).round() / 1e6;
            assert_eq!(time_s, to_the_microsecond, "{text}");
            assert_eq!(interface, "vcan0");
            assert_eq!(frame, logged.frame);
        }
    }

    #[test]
    fn parses_what_can_utils_accepts() {
        let expected = frame(0x123, &[0x11, 0x22, 0x33]);
        for text in [
            "(0000000001.500000) can0 123##0112233",
            "(0000000001.500000) can0 123##5112233",
            "(0000000001.500000) can0 123##4.11.22.33",
            "  (0000000001.5)   can0   123##4112233  R\r\n",
            "(0000000001.500000000) can0 123##f112233",
            "(0000000001.500000) can0 123##4112233\n",
        ] {
            assert_eq!(
                parse_line(text),
                Ok((1.5, "can0".to_owned(), expected)),
                "{text}"
            );
        }
        assert_eq!(
            parse_line("(0.0) vcan0 7ff##4"),
            Ok((0.0, "vcan0".to_owned(), frame(0x7FF, &[])))
        );
    }

    #[test]
    fn malformed_lines_give_their_cause() {
        use CandumpParseError as E;
        type IsExpected = fn(&E) -> bool;
        let cases: [(&str, IsExpected); 18] = [
            ("", |e| *e == E::MissingTimestamp),
            ("vcan0 123##4", |e| *e == E::MissingTimestamp),
            ("(1.0 vcan0 123##4", |e| *e == E::MissingTimestamp),
            ("(1) vcan0 123##4", |e| matches!(e, E::BadTimestamp { .. })),
            ("(1.x) vcan0 123##4", |e| {
                matches!(e, E::BadTimestamp { .. })
            }),
            ("(-1.0) vcan0 123##4", |e| {
                matches!(e, E::BadTimestamp { .. })
            }),
            ("(1.0)", |e| *e == E::MissingInterface),
            ("(1.0) vcan0", |e| *e == E::MissingFrame),
            ("(1.0) vcan0 12##4", |e| matches!(e, E::BadId { .. })),
            ("(1.0) vcan0 1G3##4", |e| matches!(e, E::BadId { .. })),
            ("(1.0) vcan0 12345678##4", |e| {
                matches!(e, E::ExtendedId { .. })
            }),
            ("(1.0) vcan0 800##4", |e| {
                *e == E::IdOutOfRange { id: 0x800 }
            }),
            ("(1.0) vcan0 123#1122", |e| matches!(e, E::NotCanFd { .. })),
            ("(1.0) vcan0 123#R", |e| matches!(e, E::NotCanFd { .. })),
            ("(1.0) vcan0 123##", |e| matches!(e, E::BadFlags { .. })),
            ("(1.0) vcan0 123##4112", |e| matches!(e, E::BadData { .. })),
            ("(1.0) vcan0 123##411zz", |e| matches!(e, E::BadData { .. })),
            ("(1.0) vcan0 123##4112233445566778899", |e| {
                *e == E::BadLength { len: 9 }
            }),
        ];
        for (text, is_expected) in cases {
            let error = parse_line(text).unwrap_err();
            assert!(is_expected(&error), "{text:?} gave {error:?}");
            assert!(!error.to_string().is_empty());
        }
        let too_long = format!("(1.0) vcan0 123##4{}", "00".repeat(65));
        assert_eq!(
            parse_line(&too_long),
            Err(CandumpParseError::BadLength { len: 65 })
        );
    }

    #[test]
    fn cansend_text_uses_the_bit_rate_switch_flag() {
        assert_eq!(cansend_text(&frame(0x00A, &[0x01, 0xFE])), "00A##101FE");
        assert_eq!(cansend_text(&frame(0x7FF, &[])), "7FF##1");
    }

    #[test]
    fn a_log_reads_complete_lines_and_names_the_bad_one() {
        let text = "(0.004000) vcan0 101##401\n\n(0.008000) vcan0 102##4\n(0.0120";
        let frames = read_log(text).unwrap();
        assert_eq!(frames.len(), 2);
        assert_eq!(frames[1].frame, frame(0x102, &[]));
        assert_eq!(frames[1].time_s, 0.008);
        let error = read_log("(0.004000) vcan0 101##401\n(0.008) vcan0 102#11\n").unwrap_err();
        assert_eq!(error.line, 2);
        assert!(matches!(error.cause, CandumpParseError::NotCanFd { .. }));
        assert!(error.to_string().starts_with("line 2: "));
    }

    #[test]
    fn bad_interface_or_time_is_invalid_input() {
        for interface in ["", "has space", "sixteen-bytes-xx"] {
            let error = CandumpWriter::new(Vec::new(), interface).unwrap_err();
            assert_eq!(error.kind(), io::ErrorKind::InvalidInput, "{interface:?}");
        }
        let mut writer = CandumpWriter::new(Vec::new(), "vcan0").unwrap();
        for time_s in [-0.001, f64::NAN, f64::INFINITY] {
            let logged = LoggedFrame {
                time_s,
                frame: frame(0x101, &[]),
            };
            let error = writer.write(&logged).unwrap_err();
            assert_eq!(error.kind(), io::ErrorKind::InvalidInput);
        }
        assert!(writer.finish().unwrap().is_empty());
    }
}
