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
    assert!(dbc.contains("SG_ faults_estop_latched : 40|1@1+"));
    assert!(dbc.contains("SG_ position_hip1_fl : 40|16@1- (0.0001,0) [-3.2768|3.2767] \"rad\""));
}
