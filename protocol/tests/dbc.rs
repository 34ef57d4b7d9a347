//! The committed DBC is what the message definitions generate.

#[test]
fn committed_dbc_is_up_to_date() {
    let mut generated = String::new();
    protocol::dbc::write_dbc(&mut generated).unwrap();
    let committed = include_str!("../hybrid_robot.dbc");
    assert!(
        generated == committed,
        "protocol/hybrid_robot.dbc is stale: run `cargo xtask dbc` and commit it"
    );
}

#[test]
fn every_message_and_flag_appears_in_the_dbc() {
    let dbc = include_str!("../hybrid_robot.dbc");
    for id in protocol::MessageId::ALL {
        let layout = id.layout();
        let header = format!("BO_ {} {}: {} ", id.raw(), layout.name, layout.wire_len);
        assert!(dbc.contains(&header), "missing {header}");
        assert!(dbc.contains(&format!("BA_ \"VFrameFormat\" BO_ {} 14;", id.raw())));
    }
    // The 6-byte E2E header: a 32-bit check value, then the low half of the counter.
    assert!(dbc.contains("SG_ E2E_Check : 0|32@1+ (1,0) [0|4294967295]"));
    assert!(dbc.contains("SG_ E2E_Counter : 32|16@1+ (1,0) [0|65535]"));
    assert!(dbc.contains("SG_ faults_estop_latched : 56|1@1+"));
    assert!(dbc.contains("SG_ position_hip1_fl : 56|16@1- (0.0001,0) [-3.2768|3.2767] \"rad\""));
    assert!(dbc.contains("SG_ epoch : 56|32@1+"));
}
