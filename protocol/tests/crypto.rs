//! The project's AES-128 and CMAC against RustCrypto's, on random keys and messages of every
//! length a frame can give.

use aes::cipher::{BlockEncrypt, KeyInit};
use cmac::Mac;
use proptest::prelude::*;
use protocol::aes::Aes128;
use protocol::cmac::CmacKey;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2_000))]

    #[test]
    fn aes_encrypts_as_rustcrypto_does(key in any::<[u8; 16]>(), block in any::<[u8; 16]>()) {
        let theirs = {
            let cipher = aes::Aes128::new(&key.into());
            let mut b = block.into();
            cipher.encrypt_block(&mut b);
            b
        };
        let ours = Aes128::new(&key).encrypt(&block);
        prop_assert_eq!(ours.as_slice(), theirs.as_slice());
    }

    #[test]
    fn cmac_tags_as_rustcrypto_does(
        key in any::<[u8; 16]>(),
        message in proptest::collection::vec(any::<u8>(), 0..80),
        split in 0_usize..80,
    ) {
        let mut mac = <cmac::Cmac<aes::Aes128> as KeyInit>::new(&key.into());
        mac.update(&message);
        let theirs = mac.finalize().into_bytes();
        let split = split.min(message.len());
        let ours = CmacKey::new(&key).tag(&[&message[..split], &message[split..]]);
        prop_assert_eq!(ours.as_slice(), theirs.as_slice());
    }
}
