//! Reading a key from 32 hex digits, its refusals, and a key never printed.

mod common;

use common::frames::OLD;
use protocol::*;

#[test]
fn a_key_reads_from_32_hex_digits() {
    let key = Key::from_hex("000102030405060708090a0b0c0d0e0f").unwrap();
    assert_eq!(key, Key(core::array::from_fn(|i| i as u8)));
    assert_eq!(
        Key::from_hex("  000102030405060708090A0B0C0D0E0F\n"),
        Ok(key),
        "upper case, surrounding whitespace"
    );
    let test_hex: String = TEST_KEY.0.iter().map(|b| format!("{b:02x}")).collect();
    assert_eq!(Key::from_hex(&test_hex), Ok(TEST_KEY));
    assert_eq!(
        Key::from_hex("ffffffffffffffffffffffffffffffff"),
        Ok(Key([0xFF; 16]))
    );
}

#[test]
fn a_key_of_the_wrong_length_is_refused_with_its_length() {
    let digits = "0123456789abcdef0123456789abcdef";
    for len in [0, 1, 2, 16, 30, 31] {
        assert_eq!(
            Key::from_hex(&digits[..len]),
            Err(KeyError::Length { digits: len }),
            "{len}"
        );
    }
    for extra in ["0", "00", "0123456789abcdef"] {
        let text = format!("{digits}{extra}");
        assert_eq!(
            Key::from_hex(&text),
            Err(KeyError::Length { digits: text.len() })
        );
    }
    assert_eq!(Key::from_hex("   \n"), Err(KeyError::Length { digits: 0 }));
    let text = KeyError::Length { digits: 31 }.to_string();
    assert!(text.contains("32") && text.contains("31"), "{text}");
}

#[test]
fn a_key_with_a_character_that_is_not_hex_is_refused_where_it_is() {
    let digits = "0123456789abcdef0123456789abcdef";
    for at in [0, 1, 2, 15, 30, 31] {
        for bad in ['g', 'x', ' ', '-', 'G'] {
            let mut text: Vec<char> = digits.chars().collect();
            text[at] = bad;
            let text: String = text.into_iter().collect();
            if bad == ' ' && (at == 0 || at == 31) {
                continue; // trimmed away: a length error instead
            }
            assert_eq!(
                Key::from_hex(&text),
                Err(KeyError::NotHex { at }),
                "{text:?}"
            );
        }
    }
    // "0x" in front of 30 digits: 32 characters, the second not hex.
    assert_eq!(
        Key::from_hex(&format!("0x{}", &digits[..30])),
        Err(KeyError::NotHex { at: 1 })
    );
    // Two bytes of UTF-8 in place of the last two digits.
    assert_eq!(
        Key::from_hex(&format!("{}é", &digits[..30])),
        Err(KeyError::NotHex { at: 30 })
    );
    let text = KeyError::NotHex { at: 5 }.to_string();
    assert!(text.contains('5'), "{text}");
}

#[test]
fn a_key_is_never_printed() {
    let key = Key::from_hex("0123456789abcdef0123456789abcdef").unwrap();
    let shown = format!("{key:?} {:?}", Session::owned(key, OLD));
    assert!(!shown.contains("01") && !shown.contains("[1,"), "{shown}");
    assert_eq!(format!("{TEST_KEY:?}"), "Key(test key)");
}
