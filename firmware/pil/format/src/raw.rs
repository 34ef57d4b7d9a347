//! The raw format (magic `PIL1`): what `pil_record` writes and the PIL image embeds and reads.
//! [`Reader`] needs no heap; `Recording` (feature `alloc`) reads and writes it whole.

use crate::cursor::Cursor;
use crate::{Error, Header};

/// The raw format's magic.
pub const MAGIC: &[u8; 4] = b"PIL1";

/// Reads raw bytes tick by tick, without a heap: the header, then each tick's frames.
#[derive(Debug, Clone)]
pub struct Reader<'a> {
    header: Header,
    cursor: Cursor<'a>,
    /// Ticks not yet read.
    left: u32,
}

impl<'a> Reader<'a> {
    /// Reads the header; [`Error::BadMagic`] or [`Error::Truncated`] if `bytes` do not start
    /// with one.
    pub fn new(bytes: &'a [u8]) -> Result<Self, Error> {
        let mut cursor = Cursor::new(bytes);
        let header = Header::read(&mut cursor, MAGIC)?;
        Ok(Self {
            header,
            cursor,
            left: header.ticks,
        })
    }

    /// The header.
    pub const fn header(&self) -> Header {
        self.header
    }

    /// The next tick's frames, `None` after the last tick the header counts. The whole tick is
    /// checked first: on [`Error::Truncated`] nothing is read, and the frames handed out are
    /// complete.
    pub fn next_tick(&mut self) -> Result<Option<Frames<'a>>, Error> {
        if self.left == 0 {
            return Ok(None);
        }
        let mut cursor = self.cursor;
        let count = cursor.u8()?;
        let body = cursor.rest();
        for _ in 0..count {
            cursor.u16()?;
            let len = cursor.u8()?;
            cursor.take(usize::from(len))?;
        }
        let used = body.len().saturating_sub(cursor.rest().len());
        let body = body.get(..used).ok_or(Error::Truncated)?;
        self.cursor = cursor;
        self.left = self.left.saturating_sub(1);
        Ok(Some(Frames {
            cursor: Cursor::new(body),
            left: count,
        }))
    }

    /// Ends reading: [`Error::TrailingBytes`] if bytes follow the last tick (ticks not read
    /// yet count as following bytes).
    pub fn finish(self) -> Result<(), Error> {
        if self.left == 0 && self.cursor.rest().is_empty() {
            Ok(())
        } else {
            Err(Error::TrailingBytes)
        }
    }
}

/// One tick's frames, as (id, data), in the order received.
#[derive(Debug, Clone)]
pub struct Frames<'a> {
    /// The tick's frames, checked by [`Reader::next_tick`].
    cursor: Cursor<'a>,
    /// Frames not yet handed out.
    left: u8,
}

impl<'a> Iterator for Frames<'a> {
    type Item = (u16, &'a [u8]);

    fn next(&mut self) -> Option<Self::Item> {
        self.left = self.left.checked_sub(1)?;
        let id = self.cursor.u16().ok()?;
        let len = self.cursor.u8().ok()?;
        Some((id, self.cursor.take(usize::from(len)).ok()?))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        (usize::from(self.left), Some(usize::from(self.left)))
    }
}

impl ExactSizeIterator for Frames<'_> {}
