//! The host build of the core on the recording's inputs, and the comparison of the frames it
//! sends with the image's, field by field.

use std::convert::Infallible;

use embedded_can::nb::Can;
use firmware::node::service::{self, Drain};
use firmware::{Config, Node, Tick, TickRate};
use pil_format::Recording;
use protocol::signal::{Field, WireType};
use protocol::{Frame, MessageId};

use super::Frames;

/// The session of the recorded run.
fn pil_session() -> protocol::Session {
    protocol::Session::owned(
        protocol::TEST_KEY,
        protocol::Epoch::new(pil_format::PIL_EPOCH),
    )
}

/// The host build of the core on the same inputs.
pub(super) fn host_replay(recording: &Recording) -> Result<Vec<Frames>, String> {
    let rate = TickRate::new(u32::from(recording.control_hz))
        .ok_or_else(|| format!("bad control rate {}", recording.control_hz))?;
    let mut node = Node::new(Config::ROBOT.at_rate(rate), pil_session())
        .map_err(|e| format!("config rejected: {e:?}"))?;
    let mut out = Vec::with_capacity(recording.ticks.len());
    for (k, frames) in recording.ticks.iter().enumerate() {
        let now = Tick(recording.first_tick.wrapping_add(k as u32));
        // The firmware's own service loop, as on the board and in the image.
        let mut port = Replay::new(frames)?;
        let limit = u32::try_from(frames.len()).unwrap_or(u32::MAX);
        let Ok(_) = service::receive(&mut node, now, &mut port, Drain::All, limit);
        let Ok(_) = service::transmit(&mut node, now, &mut port);
        out.push(
            port.sent
                .iter()
                .map(|f| (f.id(), f.data().to_vec()))
                .collect(),
        );
    }
    Ok(out)
}

/// One recorded tick as a CAN port: its frames come out of `receive`, what the node sends is
/// kept.
struct Replay {
    inbox: std::vec::IntoIter<Frame>,
    sent: Vec<Frame>,
}

impl Replay {
    fn new(frames: &[(u16, Vec<u8>)]) -> Result<Self, String> {
        let inbox = frames
            .iter()
            .map(|(id, data)| {
                Frame::new(*id, data).ok_or_else(|| {
                    format!(
                        "recorded frame {id:03X} with {} bytes is not a CAN FD frame",
                        data.len()
                    )
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            inbox: inbox.into_iter(),
            sent: Vec::new(),
        })
    }
}

impl Can for Replay {
    type Frame = Frame;
    type Error = Infallible;

    fn transmit(&mut self, frame: &Frame) -> nb::Result<Option<Frame>, Infallible> {
        self.sent.push(*frame);
        Ok(None)
    }

    fn receive(&mut self) -> nb::Result<Frame, Infallible> {
        self.inbox.next().ok_or(nb::Error::WouldBlock)
    }
}

/// The outcome of comparing the two builds.
#[derive(Default)]
pub(super) struct Check {
    /// Frames compared.
    pub(super) frames: u64,
    /// Values (signal fields) compared.
    pub(super) values: u64,
    /// Values that differ by one count.
    pub(super) off_by_one: u64,
    /// Largest difference in physical units, and where.
    pub(super) max_deviation: f64,
    pub(super) max_at: String,
}

pub(super) fn compare(host: &[Frames], pil: &[(u32, u64, Frames)]) -> Result<Check, String> {
    if host.len() != pil.len() {
        return Err(format!(
            "PIL ran {} ticks, the host {}",
            pil.len(),
            host.len()
        ));
    }
    let mut check = Check::default();
    for (k, (host_frames, (tick, _, pil_frames))) in host.iter().zip(pil).enumerate() {
        let ids = |f: &Frames| f.iter().map(|(id, _)| *id).collect::<Vec<_>>();
        if ids(host_frames) != ids(pil_frames) {
            return Err(format!(
                "tick {tick} (step {k}): PIL sent ids {:03x?}, the host {:03x?}",
                ids(pil_frames),
                ids(host_frames)
            ));
        }
        for ((id, host_data), (_, pil_data)) in host_frames.iter().zip(pil_frames) {
            check.frames += 1;
            compare_frame(*tick, *id, host_data, pil_data, &mut check)?;
        }
    }
    Ok(check)
}

fn compare_frame(
    tick: u32,
    id: u16,
    host: &[u8],
    pil: &[u8],
    check: &mut Check,
) -> Result<(), String> {
    let message =
        MessageId::from_raw(id).ok_or_else(|| format!("tick {tick}: unknown id {id:#x}"))?;
    let layout = message.layout();
    for (who, data) in [("host", host), ("PIL", pil)] {
        protocol::decode_frame(id, data).map_err(|e| {
            format!(
                "tick {tick}: {} from the {who} does not decode: {e:?}",
                layout.name
            )
        })?;
    }
    if host.len() != pil.len() {
        return Err(format!("tick {tick}: {}: lengths differ", layout.name));
    }
    let payload: usize = layout.fields.iter().map(Field::bytes).sum();
    let mut at = layout.len - payload;
    for field in layout.fields {
        for i in 0..field.count() {
            let name = match field.instances.get(i) {
                Some(instance) => format!("{}.{}_{instance}", layout.name, field.name),
                None => format!("{}.{}", layout.name, field.name),
            };
            let (a, b) = (raw(field.ty, host, at), raw(field.ty, pil, at));
            at += field.ty.bytes();
            check.values += 1;
            let counts = (a - b).abs();
            if counts == 0 {
                continue;
            }
            // Scaled quantities may differ by one count (float rounding before quantising);
            // enumerations, flags, counters and ticks must be equal.
            let scaled = field.exp10 < 0 && field.values.is_empty() && field.flags.is_empty();
            let scale = 10_f64.powi(i32::from(field.exp10));
            if !scaled || counts > 1 {
                return Err(format!(
                    "tick {tick}: {name} differs: host {} vs PIL {} {} (raw {a} vs {b})",
                    a as f64 * scale,
                    b as f64 * scale,
                    field.unit
                ));
            }
            check.off_by_one += 1;
            let deviation = counts as f64 * scale;
            if deviation > check.max_deviation {
                check.max_deviation = deviation;
                check.max_at = format!("{name} at tick {tick} ({deviation} {})", field.unit);
            }
        }
    }
    Ok(())
}

fn raw(ty: WireType, data: &[u8], at: usize) -> i64 {
    let byte = |i: usize| data.get(at + i).copied().unwrap_or(0);
    match ty {
        WireType::U8 => i64::from(byte(0)),
        WireType::I16 => i64::from(i16::from_le_bytes([byte(0), byte(1)])),
        WireType::U16 => i64::from(u16::from_le_bytes([byte(0), byte(1)])),
        WireType::U32 => i64::from(u32::from_le_bytes([byte(0), byte(1), byte(2), byte(3)])),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wheel_command(left: i16, right: i16) -> Vec<u8> {
        use protocol::{AnyMessage, DriveEnable, Torque, WheelCommand};
        let torque = [left, right].map(|raw| Torque::from_raw(raw).unwrap());
        let enable = DriveEnable::Enabled;
        AnyMessage::WheelCommand(WheelCommand { enable, torque })
            .encode(&pil_session(), 3)
            .unwrap()
            .data()
            .to_vec()
    }

    #[test]
    fn a_difference_names_the_tick_and_the_field() {
        let id = MessageId::WheelCommand.raw();
        let mut check = Check::default();
        let same = wheel_command(100, 200);
        compare_frame(5, id, &same, &same, &mut check).unwrap();
        // Three values: the enable and the two torques.
        assert_eq!((check.values, check.off_by_one), (3, 0));
        compare_frame(6, id, &same, &wheel_command(100, 201), &mut check).unwrap();
        assert_eq!(check.off_by_one, 1);
        assert!(
            check.max_at.contains("WheelCommand.torque_"),
            "{}",
            check.max_at
        );
        let error = compare_frame(7, id, &same, &wheel_command(100, 250), &mut check).unwrap_err();
        assert!(error.starts_with("tick 7: WheelCommand.torque_"), "{error}");
    }
}
