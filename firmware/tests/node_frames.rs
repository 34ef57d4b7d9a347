//! Whatever the bus delivers, the node's commands stay safe: a property test over arbitrary
//! frame sequences and tick gaps into the whole frame handler (decode, E2E, controller, encode).
//!
//! Frames are drawn so that most get past the cheap checks and reach the field decoding and the
//! controller: a known identifier with its exact wire length, arbitrary payload bytes and a
//! check value (CRC or MAC, as the identifier takes) valid in the node's session at a
//! plausible counter; besides those, corrupted copies, wrong lengths, random identifiers and
//! stale or far-ahead counters.

use firmware::limits::Joint;
use firmware::{Config, Tick};
use proptest::prelude::*;
use protocol::e2e::{protect, Freshness, HEADER_LEN};
use protocol::{decode_frame, protection_of, AnyMessage, MessageId, Session, TEST_KEY};

mod common;

const CONFIG: Config = Config::ROBOT;

/// How one frame of the test is made.
#[derive(Debug, Clone)]
enum Draw {
    /// A known id, its length, these payload bytes, a valid check, the next counter plus `skip`.
    Sealed {
        id: usize,
        payload: Vec<u8>,
        skip: u16,
    },
    /// A sealed frame with one bit flipped afterwards.
    Flipped {
        id: usize,
        payload: Vec<u8>,
        bit: usize,
    },
    /// Any id and any bytes.
    Raw { id: u16, data: Vec<u8> },
}

fn draw() -> impl Strategy<Value = Draw> {
    let ids = MessageId::ALL.len();
    let payload = prop::collection::vec(any::<u8>(), 64);
    prop_oneof![
        6 => (0..ids, payload.clone(), prop_oneof![8 => Just(0u16), 1 => any::<u16>()])
            .prop_map(|(id, payload, skip)| Draw::Sealed { id, payload, skip }),
        1 => (0..ids, payload, 0..512usize)
            .prop_map(|(id, payload, bit)| Draw::Flipped { id, payload, bit }),
        1 => (0u16..0x800, prop::collection::vec(any::<u8>(), 0..=64))
            .prop_map(|(id, data)| Draw::Raw { id, data }),
    ]
}

/// Builds the frame of `draw`, advancing the per-id counters.
fn build(draw: &Draw, counters: &mut [u32; MessageId::ALL.len()]) -> (u16, Vec<u8>) {
    let session: Session = common::SESSION;
    let sealed =
        |id: usize, payload: &[u8], skip: u16, counters: &mut [u32; MessageId::ALL.len()]| {
            let message = MessageId::ALL[id];
            let layout = message.layout();
            let mut data = vec![0; layout.wire_len];
            let end = layout.len.min(data.len());
            data[HEADER_LEN..end].copy_from_slice(&payload[..end - HEADER_LEN]);
            counters[id] = counters[id].wrapping_add(1).wrapping_add(u32::from(skip));
            // As a sender would: the check the payload's identifier (and action) takes, bound to
            // the session if it is, at the full counter, or the low half for a frame outside
            // the sequence.
            let (protection, covered) = protection_of(message, &data);
            let freshness = Freshness {
                data_id: message.data_id(),
                epoch: if protection.bound {
                    session.epoch()
                } else {
                    None
                },
                counter: if protection.sequenced {
                    counters[id]
                } else {
                    counters[id] & 0xFFFF
                },
            };
            protect(
                protection.check,
                &TEST_KEY,
                &freshness,
                &mut data[..HEADER_LEN + covered],
            );
            (message.raw(), data)
        };
    match draw {
        Draw::Sealed { id, payload, skip } => sealed(*id, payload, *skip, counters),
        Draw::Flipped { id, payload, bit } => {
            let (raw, mut data) = sealed(*id, payload, 0, counters);
            let len = data.len();
            data[(bit / 8) % len] ^= 1 << (bit % 8);
            (raw, data)
        }
        Draw::Raw { id, data } => (*id, data.clone()),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// Any frames, any gaps between ticks: every command out is finite and inside the joint and
    /// torque limits, every frame out decodes, and every rejected frame is counted.
    #[test]
    fn no_frame_sequence_yields_an_unsafe_command(
        script in prop::collection::vec((prop::collection::vec(draw(), 0..12), 1u32..30), 1..100)
    ) {
        let mut node = common::node(CONFIG);
        let mut counters = [0u32; MessageId::ALL.len()];
        let mut now = 0u32;
        let mut refused = 0u32;
        for (draws, gap) in script {
            for d in &draws {
                let (id, data) = build(d, &mut counters);
                if node.on_frame(Tick(now), id, &data).is_err() {
                    refused += 1;
                }
            }
            now = now.wrapping_add(gap);
            let (output, frames) = node.poll(Tick(now));
            for (leg, angles) in output.leg_targets_rad.iter_legs() {
                for (joint, angle) in Joint::ALL.into_iter().zip(angles) {
                    prop_assert!(
                        angle.is_finite() && CONFIG.limits.range(joint).contains(*angle),
                        "leg {leg:?} {joint:?} = {angle}"
                    );
                }
            }
            for torque in output.wheel_torque_nm {
                prop_assert!(torque.is_finite() && torque.abs() <= CONFIG.wheel_torque_limit_nm);
            }
            for frame in &frames {
                let decoded = decode_frame(frame.id(), frame.data());
                prop_assert!(decoded.is_ok(), "own frame {:03X} does not decode", frame.id());
                match decoded.map(|d| d.message) {
                    Ok(AnyMessage::WheelCommand(w)) => {
                        for t in w.torque {
                            prop_assert!(t.si().abs() <= CONFIG.wheel_torque_limit_nm + 0.01);
                        }
                    }
                    Ok(AnyMessage::LegTargets(t)) => {
                        for (i, angle) in t.position.iter().enumerate() {
                            let range = CONFIG.limits.range(Joint::ALL[i % 4]);
                            prop_assert!(
                                angle.si() >= range.min_rad - 1e-3 && angle.si() <= range.max_rad + 1e-3,
                                "LegTargets[{i}] = {}", angle.si()
                            );
                        }
                    }
                    _ => {}
                }
            }
            prop_assert_eq!(node.encode_failures(), 0);
        }
        // Every refusal was counted under its cause (the u16 counters do not wrap here).
        prop_assert_eq!(node.reject_counters().total(), refused);
    }
}
