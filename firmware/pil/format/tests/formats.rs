//! Both formats: round trips, the committed recording, and a typed error for each kind of
//! damage.

use pil_format::{compact, raw, Error, Header, Recording};

fn sample() -> Recording {
    Recording {
        control_hz: 250,
        first_tick: 7,
        ticks: vec![
            vec![(0x180, vec![1, 0, 0, 0, 5, 0, 0, 9]), (0x10, vec![])],
            vec![(0x180, vec![1, 0, 0, 0, 6, 0, 0, 9])],
            vec![],
            vec![(0x180, (0..64).collect()), (0x181, vec![0; 64])],
            vec![(0x180, vec![0; 3]), (0x181, vec![7; 1])],
        ],
    }
}

#[test]
fn both_formats_round_trip() {
    let recording = sample();
    let raw = recording.to_raw().unwrap();
    let compact = recording.to_compact().unwrap();
    assert_eq!(&raw[..4], raw::MAGIC);
    assert_eq!(&compact[..4], compact::MAGIC);
    assert_eq!(Recording::from_raw(&raw).unwrap(), recording);
    assert_eq!(Recording::from_compact(&compact).unwrap(), recording);
    assert!(compact.len() < raw.len());
}

#[test]
fn the_reader_hands_out_each_ticks_frames_without_a_heap() {
    let recording = sample();
    let bytes = recording.to_raw().unwrap();
    let mut reader = raw::Reader::new(&bytes).unwrap();
    assert_eq!(
        reader.header(),
        Header {
            control_hz: 250,
            first_tick: 7,
            ticks: 5
        }
    );
    for expected in &recording.ticks {
        let frames = reader.next_tick().unwrap().unwrap();
        assert_eq!(frames.len(), expected.len());
        let got: Vec<(u16, Vec<u8>)> = frames.map(|(id, data)| (id, data.to_vec())).collect();
        assert_eq!(&got, expected);
    }
    assert!(reader.next_tick().unwrap().is_none());
    reader.finish().unwrap();
}

/// Every length a frame can have, with zeros in runs of every phase: the run-length code
/// (checked on the first frame of each id, whose data is coded as it is).
#[test]
fn runs_cover_every_length() {
    let mut ticks = Vec::new();
    for len in 0..=255_usize {
        let frames = (0..4_u8)
            .map(|pattern| {
                let data = (0..len)
                    .map(|i| match pattern {
                        3 => 0,
                        _ if (i / 3) % 3 == usize::from(pattern) => 0,
                        _ => i as u8 | 1,
                    })
                    .collect();
                ((len * 4) as u16 + u16::from(pattern), data)
            })
            .collect();
        ticks.push(frames);
    }
    let recording = Recording {
        control_hz: 500,
        first_tick: u32::MAX,
        ticks,
    };
    let compact = recording.to_compact().unwrap();
    assert_eq!(Recording::from_compact(&compact).unwrap(), recording);
}

/// `firmware/pil/recording.pil` reads, and writes back to the same bytes in both formats.
#[test]
fn the_committed_recording_re_encodes_byte_for_byte() {
    let committed = include_bytes!("../../recording.pil");
    let recording = Recording::from_compact(committed).unwrap();
    assert!(recording.ticks.len() > 1000);
    assert_eq!(recording.to_compact().unwrap(), committed);
    let raw = recording.to_raw().unwrap();
    assert_eq!(Recording::from_raw(&raw).unwrap(), recording);
}

#[test]
fn a_wrong_magic_is_named() {
    let raw = sample().to_raw().unwrap();
    let compact = sample().to_compact().unwrap();
    let expected_raw = Error::BadMagic {
        expected: raw::MAGIC,
    };
    let expected_compact = Error::BadMagic {
        expected: compact::MAGIC,
    };
    assert_eq!(Recording::from_raw(&compact).unwrap_err(), expected_raw);
    assert_eq!(raw::Reader::new(&compact).unwrap_err(), expected_raw);
    assert_eq!(Recording::from_compact(&raw).unwrap_err(), expected_compact);
    let mut damaged = raw.clone();
    damaged[3] = b'2';
    assert_eq!(Recording::from_raw(&damaged).unwrap_err(), expected_raw);
    assert!(expected_raw.to_string().contains("PIL1"));
}

#[test]
fn every_truncation_is_an_error() {
    let recording = sample();
    let raw = recording.to_raw().unwrap();
    let compact = recording.to_compact().unwrap();
    for len in 0..raw.len() {
        assert_eq!(
            Recording::from_raw(&raw[..len]).unwrap_err(),
            Error::Truncated,
            "{len} bytes"
        );
    }
    for len in 0..compact.len() {
        assert_eq!(
            Recording::from_compact(&compact[..len]).unwrap_err(),
            Error::Truncated,
            "{len} bytes"
        );
    }
    assert_eq!(
        raw::Reader::new(&raw[..Header::LEN - 1]).unwrap_err(),
        Error::Truncated
    );
}

#[test]
fn a_truncated_tick_reads_nothing() {
    let raw = sample().to_raw().unwrap();
    // The header and the first tick's count and first frame, not its second.
    let mut reader = raw::Reader::new(&raw[..Header::LEN + 1 + 3 + 8]).unwrap();
    assert_eq!(reader.next_tick().unwrap_err(), Error::Truncated);
    assert_eq!(reader.next_tick().unwrap_err(), Error::Truncated);
    assert_eq!(reader.finish().unwrap_err(), Error::TrailingBytes);
}

#[test]
fn bytes_after_the_last_tick_are_an_error() {
    let mut raw = sample().to_raw().unwrap();
    let mut compact = sample().to_compact().unwrap();
    raw.push(0);
    compact.push(0);
    assert_eq!(Recording::from_raw(&raw).unwrap_err(), Error::TrailingBytes);
    assert_eq!(
        Recording::from_compact(&compact).unwrap_err(),
        Error::TrailingBytes
    );
}

#[test]
fn a_run_past_its_frame_is_an_error() {
    // One tick, one frame of 2 bytes, coded as a run of 3 zeros.
    let mut bytes = compact::MAGIC.to_vec();
    bytes.extend_from_slice(&250_u16.to_le_bytes());
    bytes.extend_from_slice(&0_u32.to_le_bytes());
    bytes.extend_from_slice(&1_u32.to_le_bytes());
    bytes.extend_from_slice(&[1, 0x80, 0x01, 2, 0x82]);
    assert_eq!(
        Recording::from_compact(&bytes).unwrap_err(),
        Error::RunOverrun
    );
    // The same with 2 zeros reads.
    *bytes.last_mut().unwrap() = 0x81;
    assert_eq!(
        Recording::from_compact(&bytes).unwrap().ticks,
        vec![vec![(0x180, vec![0, 0])]]
    );
}

#[test]
fn what_the_formats_cannot_hold_is_not_written() {
    let mut recording = Recording::default();
    recording.ticks.push(vec![(1, vec![0; 256])]);
    assert_eq!(recording.to_raw().unwrap_err(), Error::FrameTooLong);
    assert_eq!(recording.to_compact().unwrap_err(), Error::FrameTooLong);
    recording.ticks = vec![vec![(1, vec![]); 256]];
    assert_eq!(recording.to_raw().unwrap_err(), Error::TooManyFrames);
}
