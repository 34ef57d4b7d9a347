//! A whole recording in memory (feature `alloc`): reading and writing both formats.

use alloc::collections::BTreeMap;
use alloc::vec::Vec;

use crate::cursor::Cursor;
use crate::{compact, raw, Error, Header};

/// One frame: id and data.
pub type Frame = (u16, Vec<u8>);

/// The frames the firmware received, tick by tick.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Recording {
    /// Control rate, Hz.
    pub control_hz: u16,
    /// The first tick's number.
    pub first_tick: u32,
    /// Per tick, its frames in the order received.
    pub ticks: Vec<Vec<Frame>>,
}

impl Recording {
    /// Reads the raw format.
    pub fn from_raw(bytes: &[u8]) -> Result<Self, Error> {
        let mut reader = raw::Reader::new(bytes)?;
        let header = reader.header();
        let mut ticks = Vec::with_capacity(capacity(header, bytes));
        while let Some(frames) = reader.next_tick()? {
            ticks.push(frames.map(|(id, data)| (id, data.to_vec())).collect());
        }
        reader.finish()?;
        Ok(Self::with_header(header, ticks))
    }

    /// Writes the raw format.
    pub fn to_raw(&self) -> Result<Vec<u8>, Error> {
        self.write(raw::MAGIC, |_, data, out| out.extend_from_slice(data))
    }

    /// Reads the compact format.
    pub fn from_compact(bytes: &[u8]) -> Result<Self, Error> {
        let mut cursor = Cursor::new(bytes);
        let header = Header::read(&mut cursor, compact::MAGIC)?;
        let mut previous = BTreeMap::new();
        let mut ticks = Vec::with_capacity(capacity(header, bytes));
        let mut buffer = [0_u8; u8::MAX as usize];
        for _ in 0..header.ticks {
            let count = cursor.u8()?;
            let mut frames = Vec::with_capacity(usize::from(count));
            for _ in 0..count {
                let id = cursor.u16()?;
                let len = cursor.u8()?;
                let delta = buffer
                    .get_mut(..usize::from(len))
                    .ok_or(Error::FrameTooLong)?;
                compact::decode_runs(&mut cursor, delta)?;
                let data = xor(previous.get(&id), delta);
                previous.insert(id, data.clone());
                frames.push((id, data));
            }
            ticks.push(frames);
        }
        if !cursor.rest().is_empty() {
            return Err(Error::TrailingBytes);
        }
        Ok(Self::with_header(header, ticks))
    }

    /// Writes the compact format.
    pub fn to_compact(&self) -> Result<Vec<u8>, Error> {
        let mut previous = BTreeMap::new();
        self.write(compact::MAGIC, |id, data, out| {
            let delta = xor(previous.get(&id), data);
            previous.insert(id, data.to_vec());
            compact::encode_runs(&delta, out);
        })
    }

    fn with_header(header: Header, ticks: Vec<Vec<Frame>>) -> Self {
        Self {
            control_hz: header.control_hz,
            first_tick: header.first_tick,
            ticks,
        }
    }

    /// The layout both formats share, with each frame's data written by `data`.
    fn write(
        &self,
        magic: &[u8; 4],
        mut data: impl FnMut(u16, &[u8], &mut Vec<u8>),
    ) -> Result<Vec<u8>, Error> {
        let header = Header {
            control_hz: self.control_hz,
            first_tick: self.first_tick,
            ticks: u32::try_from(self.ticks.len()).map_err(|_| Error::TooManyTicks)?,
        };
        let mut out = Vec::new();
        header.write(magic, &mut out);
        for frames in &self.ticks {
            out.push(u8::try_from(frames.len()).map_err(|_| Error::TooManyFrames)?);
            for (id, bytes) in frames {
                let len = u8::try_from(bytes.len()).map_err(|_| Error::FrameTooLong)?;
                out.extend_from_slice(&id.to_le_bytes());
                out.push(len);
                data(*id, bytes, &mut out);
            }
        }
        Ok(out)
    }
}

/// `bytes` XORed with `previous` (zeros past its end).
fn xor(previous: Option<&Vec<u8>>, bytes: &[u8]) -> Vec<u8> {
    let previous = previous.map_or(&[][..], Vec::as_slice);
    bytes
        .iter()
        .enumerate()
        .map(|(i, b)| b ^ previous.get(i).copied().unwrap_or(0))
        .collect()
}

/// Ticks to reserve room for: the header's count, but no more than the bytes could hold (one
/// byte a tick at least), so that a damaged count does not reserve gigabytes.
fn capacity(header: Header, bytes: &[u8]) -> usize {
    usize::try_from(header.ticks)
        .unwrap_or(usize::MAX)
        .min(bytes.len())
}
