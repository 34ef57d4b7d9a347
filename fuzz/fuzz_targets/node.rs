//! The firmware's whole frame handler: frames and ticks into `firmware::Node`, which must
//! never panic (overflow checks are on), and whose every command stays finite and in limits.
//! A record whose identifier has the seal bit set is sealed in the node's session first, so
//! that fuzzed payloads reach the decoders and the controller.
#![no_main]

use firmware::limits::Joint;
use firmware::{Config, Node, Tick};
use libfuzzer_sys::fuzz_target;

#[path = "seal.rs"]
mod seal;

fuzz_target!(|input: &[u8]| {
    let config = Config::ROBOT;
    let Ok(mut node) = Node::new(config, seal::SESSION) else {
        return;
    };
    let mut counters = [0; protocol::MessageId::ALL.len()];
    let mut now = 0u32;
    let mut rest = input;
    // Records: [gap, id low, id high (| seal bit), length, bytes…]; a gap > 0 runs that many
    // ticks.
    while let [gap, id_low, id_high, len, tail @ ..] = rest {
        for _ in 0..(*gap % 8) {
            now = now.wrapping_add(1);
            let (output, _) = node.poll(Tick(now));
            for (i, angle) in output.leg_targets_rad.iter().enumerate() {
                let range = config.limits.range(Joint::ALL[i % 4]);
                assert!(
                    angle.is_finite() && range.contains(*angle),
                    "joint {i} = {angle}"
                );
            }
            for torque in output.wheel_torque_nm {
                assert!(torque.is_finite() && torque.abs() <= config.wheel_torque_limit_nm);
            }
        }
        let id = u16::from_le_bytes([*id_low, *id_high]) & 0x7FF;
        let len = usize::from(*len).min(64).min(tail.len());
        let (data, next) = tail.split_at(len);
        let sealed = (id_high & seal::SEAL != 0)
            .then(|| seal::seal(id, data, &mut counters))
            .flatten();
        let _ = node.on_frame(Tick(now), id, sealed.as_deref().unwrap_or(data));
        rest = next;
    }
});
