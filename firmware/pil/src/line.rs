//! A line of output built in a fixed buffer and written with one semihosting call.

use cortex_m_semihosting::hio::HostStream;

/// Longest line: `F 7ff ` and 64 bytes in hex.
const CAPACITY: usize = 160;

/// One output line.
pub struct Line {
    buf: [u8; CAPACITY],
    len: usize,
}

impl Line {
    pub const fn new() -> Self {
        Self {
            buf: [0; CAPACITY],
            len: 0,
        }
    }

    pub fn str(&mut self, text: &str) -> &mut Self {
        for &b in text.as_bytes() {
            self.byte(b);
        }
        self
    }

    pub fn dec(&mut self, mut value: u32) -> &mut Self {
        let mut digits = [0_u8; 10];
        let mut n = 0;
        loop {
            if let Some(d) = digits.get_mut(n) {
                *d = b'0' + (value % 10) as u8;
            }
            n += 1;
            value /= 10;
            if value == 0 || n >= digits.len() {
                break;
            }
        }
        for i in (0..n).rev() {
            if let Some(&d) = digits.get(i) {
                self.byte(d);
            }
        }
        self
    }

    pub fn hex(&mut self, bytes: &[u8]) -> &mut Self {
        for &b in bytes {
            self.byte(nibble(b >> 4));
            self.byte(nibble(b & 0xF));
        }
        self
    }

    /// Ends the line and writes it.
    pub fn send(&mut self, out: &mut HostStream) {
        self.byte(b'\n');
        let _ = out.write_all(self.buf.get(..self.len).unwrap_or(&[]));
        self.len = 0;
    }

    fn byte(&mut self, b: u8) {
        if let Some(slot) = self.buf.get_mut(self.len) {
            *slot = b;
            self.len += 1;
        }
    }
}

fn nibble(n: u8) -> u8 {
    match n {
        0..=9 => b'0' + n,
        _ => b'a' + (n - 10),
    }
}
