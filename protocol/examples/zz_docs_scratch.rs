use protocol::*;
fn hex(d: &[u8]) -> String { d.iter().map(|b| format!("{b:02X}")).collect() }
fn main() {
    let c = classic_latch(NodeId::Tool, 0).unwrap();
    let f = AnyMessage::EStop(EStop::latch(NodeId::Tool)).encode(&Session::unjoined(TEST_KEY), 0).unwrap();
    println!("classic len {} : 000#{}", c.data().len(), hex(c.data()));
    println!("fd len {} : 000##1{}", f.data().len(), hex(f.data()));
    // accepted by owner and by an unjoined member, twice (unsequenced)
    let mut owner = Receiver::owner(Session::owned(TEST_KEY, Epoch::new(5)));
    let mut member = Receiver::member(TEST_KEY);
    for fr in [&c, &f, &c, &f] {
        println!("owner {:?}", owner.receive(fr.id(), fr.data()).map(|a| a.status));
        println!("member {:?}", member.receive(fr.id(), fr.data()).map(|a| a.status));
    }
    // other key: latch still valid (CRC, key-independent)?
    let g = AnyMessage::EStop(EStop::latch(NodeId::Tool)).encode(&Session::unjoined(Key([0;16])), 0).unwrap();
    println!("same bytes with another key: {}", g.data() == f.data());
    // classic with counter 1
    println!("classic c1: {}", hex(classic_latch(NodeId::Tool, 1).unwrap().data()));
    // release unjoined -> error
    println!("release unjoined: {:?}", AnyMessage::EStop(EStop::release(NodeId::Tool, ReleaseToken::new(3))).encode(&Session::unjoined(TEST_KEY), 0).err());
    for id in MessageId::ALL { let l = id.layout(); println!("{:?} 0x{:03X} len {} wire {} {:?}", id, id.raw(), l.len, l.wire_len, l.protection); }
}
