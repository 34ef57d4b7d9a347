//! `cargo xtask frame …`: composes valid frames for `cansend` — the E-stop latch, a release,
//! an operator command — sealed as the protocol requires (CRC, or CMAC with the key, in the
//! controller's session), so that nobody types hex by hand.
//!
//! A latch is bound to nothing and is the same on every robot. A release and a command are
//! bound to the session: the controller's epoch and a session time come from its latest
//! announcement (`Announce`, id 0x020), the release token from its status (`ControllerStatus`,
//! id 0x400); `cantools decode` with the DBC shows both (see `docs/protocol.md`). The frame's
//! counter is the session time given, so it is fresh until a later frame of the same
//! identifier is accepted.

use std::path::PathBuf;

use protocol::{
    AnyMessage, BodyHeight, EStop, Epoch, Frame, GroundSpeed, Key, NodeId, ReleaseToken, Session,
    SessionTime, SpeedScale, TeleopCommand, YawRate, TEST_KEY,
};

pub const USAGE: &str = "\
cargo xtask frame latch [--source tool|teleop] [--classic] [--bus IFACE]
cargo xtask frame release --epoch N --time-ms T --token N [--key-file FILE] [--bus IFACE]
cargo xtask frame command MODE --epoch N --time-ms T [--height-m H] [--speed-pct P]
                          [--speed-m-s V] [--yaw-rate-rad-s W] [--key-file FILE] [--bus IFACE]
  MODE: the report's keys W S A L K X, or stand, fold, drive, walk; IFACE defaults to vcan0;
  --time-ms is the Announce's `time` in ms (cantools shows it in seconds); the frame is
  found by the controller for about 98 s after that time;
  without --key-file the public test key of the simulation is used";

/// What the command line asks for.
#[derive(Debug, Clone, PartialEq)]
struct Request {
    message: AnyMessage,
    source: NodeId,
    classic: bool,
    epoch: Option<u32>,
    time_ms: Option<u32>,
    key_file: Option<PathBuf>,
    bus: String,
}

pub fn run(args: &[String]) -> Result<(), String> {
    let request = parse(args)?;
    let key = match &request.key_file {
        Some(path) => read_key(path)?,
        None => TEST_KEY,
    };
    let frame = compose(&request, key)?;
    println!("cansend {} {}", request.bus, cansend_text(&frame));
    eprintln!("frame: {:?}", request.message);
    Ok(())
}

fn read_key(path: &PathBuf) -> Result<Key, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read the key file {}: {e}", path.display()))?;
    Key::from_hex(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// The frame for `request`, sealed with `key`.
fn compose(request: &Request, key: Key) -> Result<Frame, String> {
    let session = match (request.epoch, request.time_ms) {
        (Some(epoch), Some(time_ms)) => {
            Session::owned(key, Epoch::new(epoch)).at(SessionTime::from_ms(time_ms))
        }
        _ => Session::unjoined(key),
    };
    let counter = request.time_ms.unwrap_or(0);
    if request.classic {
        return protocol::classic_latch(request.source, 0)
            .ok_or_else(|| "the classic latch could not be encoded".to_string());
    }
    request
        .message
        .encode(&session, counter)
        .map_err(|e| match e {
            protocol::EncodeError::NoSession => {
                "this frame is bound to the controller's session: give --epoch and --time-ms (from \
             its latest Announce, id 0x020)"
                    .to_string()
            }
            other => format!("the frame could not be encoded: {other:?}"),
        })
}

/// `cansend`'s text for `frame`: `ID#DATA` for a classic frame (up to 8 bytes, the classic
/// latch), `ID##FLAGSDATA` for CAN FD with bit-rate switch.
fn cansend_text(frame: &Frame) -> String {
    let hex: String = frame.data().iter().map(|b| format!("{b:02X}")).collect();
    if frame.data().len() <= 8 {
        format!("{:03X}#{hex}", frame.id())
    } else {
        format!("{:03X}##1{hex}", frame.id())
    }
}

fn parse(args: &[String]) -> Result<Request, String> {
    let (kind, rest) = args
        .split_first()
        .ok_or_else(|| format!("what frame?\n{USAGE}"))?;
    let mut request = Request {
        message: AnyMessage::EStop(EStop::latch(NodeId::Tool)),
        source: NodeId::Tool,
        classic: false,
        epoch: None,
        time_ms: None,
        key_file: None,
        bus: "vcan0".into(),
    };
    let mut token = None;
    let mut mode = None;
    let mut height_m = 0.0_f32;
    let mut speed_pct = 100.0_f32;
    let mut speed_m_s = 0.0_f32;
    let mut yaw_rate_rad_s = 0.0_f32;
    let mut words = rest.iter();
    while let Some(word) = words.next() {
        let mut value = |flag: &str| {
            words
                .next()
                .cloned()
                .ok_or_else(|| format!("{flag} needs a value\n{USAGE}"))
        };
        match word.as_str() {
            "--source" => request.source = parse_source(&value("--source")?)?,
            "--classic" => request.classic = true,
            "--epoch" => request.epoch = Some(number("--epoch", &value("--epoch")?)?),
            "--time-ms" => request.time_ms = Some(number("--time-ms", &value("--time-ms")?)?),
            "--token" => token = Some(number::<u16>("--token", &value("--token")?)?),
            "--key-file" => request.key_file = Some(value("--key-file")?.into()),
            "--bus" => request.bus = value("--bus")?,
            "--height-m" => height_m = number("--height-m", &value("--height-m")?)?,
            "--speed-pct" => speed_pct = number("--speed-pct", &value("--speed-pct")?)?,
            "--speed-m-s" => speed_m_s = number("--speed-m-s", &value("--speed-m-s")?)?,
            "--yaw-rate-rad-s" => {
                yaw_rate_rad_s = number("--yaw-rate-rad-s", &value("--yaw-rate-rad-s")?)?
            }
            other if kind == "command" && mode.is_none() && !other.starts_with("--") => {
                mode = Some(teleop_core::scenario::parse_mode(other).ok_or_else(|| {
                    format!(
                        "unknown mode `{other}`: use {}",
                        teleop_core::scenario::MODE_NAMES
                    )
                })?);
            }
            other => return Err(format!("unknown option `{other}`\n{USAGE}")),
        }
    }
    request.message = match kind.as_str() {
        "latch" => AnyMessage::EStop(EStop::latch(request.source)),
        "release" => {
            let token = token.ok_or_else(|| {
                "a release needs --token: the release_token of the controller's status \
                 (ControllerStatus, id 0x400) while it reports EStop"
                    .to_string()
            })?;
            AnyMessage::EStop(EStop::release(request.source, ReleaseToken::new(token)))
        }
        "command" => AnyMessage::TeleopCommand(TeleopCommand {
            mode: mode.ok_or_else(|| format!("a command needs a MODE\n{USAGE}"))?,
            body_height: BodyHeight::from_si(height_m)
                .ok_or_else(|| format!("--height-m {height_m} is outside −0.10…0.12 m"))?,
            speed_scale: SpeedScale::from_si(speed_pct)
                .ok_or_else(|| format!("--speed-pct {speed_pct} is outside 0…100"))?,
            speed: GroundSpeed::from_si(speed_m_s)
                .ok_or_else(|| format!("--speed-m-s {speed_m_s} is outside −2…2 m/s"))?,
            yaw_rate: YawRate::from_si(yaw_rate_rad_s).ok_or_else(|| {
                format!("--yaw-rate-rad-s {yaw_rate_rad_s} is outside −3…3 rad/s")
            })?,
        }),
        other => return Err(format!("unknown frame `{other}`\n{USAGE}")),
    };
    if request.classic && kind != "latch" {
        return Err("--classic is for the latch only (an E-stop panel's 8-byte frame)".into());
    }
    Ok(request)
}

fn parse_source(text: &str) -> Result<NodeId, String> {
    match text {
        "tool" => Ok(NodeId::Tool),
        "teleop" => Ok(NodeId::Teleop),
        other => Err(format!("--source {other}: use tool or teleop")),
    }
}

fn number<T: std::str::FromStr>(flag: &str, text: &str) -> Result<T, String> {
    text.parse()
        .map_err(|_| format!("{flag} {text}: not a number of the right range"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use protocol::{E2eStatus, EStopAction, Receiver, TeleopMode};

    fn args(text: &str) -> Vec<String> {
        text.split_whitespace().map(String::from).collect()
    }

    fn frame(text: &str) -> Frame {
        compose(&parse(&args(text)).unwrap(), TEST_KEY).unwrap()
    }

    #[test]
    fn a_latch_is_the_constant_frame_any_node_accepts() {
        let fd = frame("latch");
        let classic = frame("latch --classic");
        assert_eq!(classic.data().len(), protocol::CLASSIC_LATCH_LEN);
        assert!(cansend_text(&classic).starts_with("000#"));
        assert!(cansend_text(&fd).starts_with("000##1"));
        let mut unjoined = Receiver::member(TEST_KEY);
        for f in [&fd, &classic, &fd] {
            let accepted = unjoined.receive(f.id(), f.data()).unwrap();
            assert!(matches!(
                accepted.message,
                AnyMessage::EStop(EStop {
                    action: EStopAction::Latch,
                    ..
                })
            ));
        }
    }

    #[test]
    fn a_release_and_a_command_are_accepted_in_their_session_and_nowhere_else() {
        let session = Session::owned(TEST_KEY, Epoch::new(41)).at(SessionTime::from_ms(90_000));
        let mut controller = Receiver::owner(session);
        controller.set_time(SessionTime::from_ms(90_000));
        let release = frame("release --epoch 41 --time-ms 90000 --token 3");
        let accepted = controller.receive(release.id(), release.data()).unwrap();
        assert_eq!(accepted.status, E2eStatus::Initial);
        let command = frame("command l --epoch 41 --time-ms 90000");
        let accepted = controller.receive(command.id(), command.data()).unwrap();
        assert!(matches!(
            accepted.message,
            AnyMessage::TeleopCommand(TeleopCommand {
                mode: TeleopMode::TrotForward,
                ..
            })
        ));
        // Sent again: a replay. In another session: not authentic.
        assert!(controller.receive(command.id(), command.data()).is_err());
        let mut other = Receiver::owner(Session::owned(TEST_KEY, Epoch::new(42)));
        other.set_time(SessionTime::from_ms(90_000));
        assert!(other.receive(command.id(), command.data()).is_err());
    }

    #[test]
    fn bad_requests_say_what_is_missing() {
        let error = |text: &str| {
            parse(&args(text))
                .and_then(|r| compose(&r, TEST_KEY))
                .unwrap_err()
        };
        assert!(error("release --epoch 1 --time-ms 5").contains("--token"));
        assert!(error("command l").contains("--epoch and --time-ms"));
        assert!(error("command q --epoch 1 --time-ms 5").contains("unknown mode"));
        assert!(error("command l --height-m 3 --epoch 1 --time-ms 5").contains("outside"));
        assert!(error("release --classic --token 1").contains("latch only"));
        assert!(error("latch --speed").contains("unknown option"));
        assert!(error("").contains("what frame"));
    }
}
