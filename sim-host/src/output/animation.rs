//! The run as an animated GIF: rendered frames halved in size, quantised to 256 colours
//! (NeuQuant) and written one by one as they come, so memory stays one frame deep however long
//! the run. No external encoder.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use crate::output::output_error::OutputError;

/// NeuQuant's sampling: 1 is the slowest and best, 30 the fastest; 10 quantises a 320 × 240
/// frame in a few milliseconds with no visible banding on the robot.
const QUANTISER_SPEED: i32 = 10;

/// An animation being written.
pub struct Animation {
    path: PathBuf,
    encoder: gif::Encoder<BufWriter<File>>,
    /// Full frame size, px.
    source_px: (u32, u32),
    /// Each frame shows this long, hundredths of a second.
    delay_cs: u16,
    frames: usize,
    /// The halved frame, reused.
    scaled: Vec<u8>,
}

impl std::fmt::Debug for Animation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Animation")
            .field("path", &self.path)
            .field("frames", &self.frames)
            .finish_non_exhaustive()
    }
}

impl Animation {
    /// A looping GIF at `path` of frames `source_px` big (halved), each shown `delay_cs`
    /// hundredths of a second.
    pub fn create(path: &Path, source_px: (u32, u32), delay_cs: u16) -> Result<Self, OutputError> {
        let io = |source| OutputError::Io {
            path: path.to_owned(),
            source,
        };
        let (width, height) = half(source_px);
        let (w, h) = (
            u16::try_from(width).map_err(|_| too_large(path, source_px))?,
            u16::try_from(height).map_err(|_| too_large(path, source_px))?,
        );
        let file = File::create(path).map_err(io)?;
        let mut encoder = gif::Encoder::new(BufWriter::new(file), w, h, &[])
            .map_err(|e| encode_error(path, e))?;
        encoder
            .set_repeat(gif::Repeat::Infinite)
            .map_err(|e| encode_error(path, e))?;
        Ok(Self {
            path: path.to_owned(),
            encoder,
            source_px,
            delay_cs,
            frames: 0,
            scaled: Vec::with_capacity((width * height * 3) as usize),
        })
    }

    /// Appends one frame: `rgb` holds the source size's pixels, 8-bit RGB, rows top to bottom.
    pub fn push(&mut self, rgb: &[u8]) -> Result<(), OutputError> {
        let (width, height) = self.source_px;
        if rgb.len() != (width * height * 3) as usize {
            return Err(OutputError::FrameSize {
                path: self.path.clone(),
                bytes: rgb.len(),
                width,
                height,
            });
        }
        halve(rgb, self.source_px, &mut self.scaled);
        let (w, h) = half(self.source_px);
        let mut frame =
            gif::Frame::from_rgb_speed(w as u16, h as u16, &self.scaled, QUANTISER_SPEED);
        frame.delay = self.delay_cs;
        self.encoder
            .write_frame(&frame)
            .map_err(|e| encode_error(&self.path, e))?;
        self.frames += 1;
        Ok(())
    }

    /// Frames written so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Ends the file; returns its path.
    pub fn finish(self) -> Result<PathBuf, OutputError> {
        let path = self.path;
        let writer = self
            .encoder
            .into_inner()
            .map_err(|e| encode_error(&path, e))?;
        writer.into_inner().map_err(|e| OutputError::Io {
            path: path.clone(),
            source: e.into_error(),
        })?;
        Ok(path)
    }
}

fn half((width, height): (u32, u32)) -> (u32, u32) {
    ((width / 2).max(1), (height / 2).max(1))
}

/// `rgb` (`size` px) halved into `out`: each pixel the mean of a 2 × 2 block.
fn halve(rgb: &[u8], (width, height): (u32, u32), out: &mut Vec<u8>) {
    let (w, h) = half((width, height));
    out.clear();
    let at = |x: u32, y: u32, c: u32| {
        let x = x.min(width - 1);
        let y = y.min(height - 1);
        u32::from(rgb[((y * width + x) * 3 + c) as usize])
    };
    for y in 0..h {
        for x in 0..w {
            for c in 0..3 {
                let sum = at(2 * x, 2 * y, c)
                    + at(2 * x + 1, 2 * y, c)
                    + at(2 * x, 2 * y + 1, c)
                    + at(2 * x + 1, 2 * y + 1, c);
                out.push(((sum + 2) / 4) as u8);
            }
        }
    }
}

fn too_large(path: &Path, (width, height): (u32, u32)) -> OutputError {
    OutputError::FrameSize {
        path: path.to_owned(),
        bytes: (width as usize) * (height as usize) * 3,
        width,
        height,
    }
}

fn encode_error(path: &Path, source: gif::EncodingError) -> OutputError {
    OutputError::Gif {
        path: path.to_owned(),
        source,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_go_out_halved_and_a_decoder_reads_them_back() {
        let dir = std::env::temp_dir().join(format!("animation-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.gif");
        let mut animation = Animation::create(&path, (8, 6), 25).unwrap();
        let red: Vec<u8> = (0..8 * 6).flat_map(|_| [200, 10, 10]).collect();
        let blue: Vec<u8> = (0..8 * 6).flat_map(|_| [10, 10, 200]).collect();
        animation.push(&red).unwrap();
        animation.push(&blue).unwrap();
        assert!(animation.push(&red[..9]).is_err());
        animation.finish().unwrap();
        let mut options = gif::DecodeOptions::new();
        options.set_color_output(gif::ColorOutput::RGBA);
        let mut decoder = options.read_info(File::open(&path).unwrap()).unwrap();
        assert_eq!((decoder.width(), decoder.height()), (4, 3));
        let mut colours = Vec::new();
        while let Some(frame) = decoder.read_next_frame().unwrap() {
            assert_eq!(frame.delay, 25);
            colours.push([frame.buffer[0], frame.buffer[1], frame.buffer[2]]);
        }
        assert_eq!(colours.len(), 2);
        assert!(colours[0][0] > 150 && colours[1][2] > 150, "{colours:?}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
