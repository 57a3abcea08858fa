//! The one PNG encoder of every 8-bit PNG `whitted` writes: [`PngRows`] takes an image's rows
//! top to bottom, in any number of calls, and gives the file's bytes. Each row is filtered
//! (adaptive: the filter the `png` crate's heuristic picks for the row) and compressed
//! (`fdeflate`, the crate's fast setting) as it comes, so the streamed images of `streamed.rs` compress a PNG
//! band by band while the render runs, and [`encode_png`] (a whole image at once) gives the
//! same bytes: they depend on the rows alone, not on how they were handed over.
//!
//! ```text
//! rows (RGB, top to bottom) --PngRows::push--> png::StreamWriter: filter, fdeflate --> Sink
//!                            --PngRows::finish--> the file's bytes (IDAT chunks, IEND)
//! ```

use std::io::Write;
use std::sync::{Arc, Mutex, PoisonError};

use crate::error::{Error, Result};

/// Where the encoder puts the file's bytes as it makes them: a buffer [`PngRows`] keeps a
/// handle on, as `png`'s row-by-row writer owns its output to the end.
#[derive(Clone, Default)]
struct Sink(Arc<Mutex<Vec<u8>>>);

impl Write for Sink {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        let mut out = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        out.try_reserve(bytes.len())
            .map_err(|_| std::io::Error::from(std::io::ErrorKind::OutOfMemory))?;
        out.extend_from_slice(bytes);
        Ok(bytes.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Compressed bytes per `IDAT` chunk (the last one holds the rest).
const IDAT_BYTES: usize = 1 << 18;

/// A PNG being encoded row by row: 8-bit RGB, `width` x `height`.
pub(super) struct PngRows {
    rows: png::StreamWriter<'static, Sink>,
    out: Sink,
    /// Bytes of rows still to come.
    left: usize,
}

impl PngRows {
    /// The encoder of a `width` x `height` image; the header is written at once.
    pub(super) fn new(width: u32, height: u32) -> Result<PngRows> {
        let out = Sink::default();
        let mut encoder = png::Encoder::new(out.clone(), width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_compression(png::Compression::Fast);
        encoder.set_filter(png::Filter::Adaptive);
        let rows = encoder
            .write_header()
            .and_then(|w| w.into_stream_writer_with_size(IDAT_BYTES))
            .map_err(cannot)?;
        let left = width as usize * height as usize * 3;
        Ok(PngRows { rows, out, left })
    }

    /// Takes the next rows' RGB bytes (top to bottom; a row may come in pieces); more bytes
    /// than the image has left is an error.
    pub(super) fn push(&mut self, rgb: &[u8]) -> Result<()> {
        if rgb.len() > self.left {
            return Err(Error::Other(format!(
                "cannot encode PNG: {} bytes of rows given where {} were left",
                rgb.len(),
                self.left
            )));
        }
        self.left -= rgb.len();
        self.rows.write_all(rgb).map_err(|e| cannot(e.into()))
    }

    /// The file's bytes, once every row was pushed (an error otherwise).
    pub(super) fn finish(self) -> Result<Vec<u8>> {
        let PngRows { rows, out, .. } = self;
        rows.finish().map_err(cannot)?;
        Ok(std::mem::take(
            &mut *out.0.lock().unwrap_or_else(PoisonError::into_inner),
        ))
    }
}

fn cannot(e: png::EncodingError) -> Error {
    Error::Other(format!("cannot encode PNG: {e}"))
}

/// The PNG of the 8-bit RGB image `data` (`w` x `h`, rows top to bottom): [`PngRows`] handed
/// every row at once.
pub(super) fn encode_png(w: u32, h: u32, data: &[u8]) -> Result<Vec<u8>> {
    let mut png = PngRows::new(w, h)?;
    png.push(data)?;
    png.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::Rng;

    /// Rows of noise, flat runs and gradients, so that every filter wins some row.
    fn image(w: u32, h: u32, rng: &mut Rng) -> Vec<u8> {
        let row = w as usize * 3;
        (0..h as usize * row)
            .map(|i| match (i / row) % 4 {
                0 => (rng.next() % 256) as u8,
                1 => 7,
                2 => (i % row) as u8,
                _ => ((i / row) * 3 + (i % row) / 3) as u8,
            })
            .collect()
    }

    #[test]
    fn a_png_reads_back_as_its_rows_whatever_the_pieces_they_came_in() {
        let mut rng = Rng(31);
        for (w, h) in [(1, 1), (3, 2), (17, 40), (300, 9)] {
            let data = image(w, h, &mut rng);
            let whole = encode_png(w, h, &data).unwrap();
            let back = image::load_from_memory_with_format(&whole, image::ImageFormat::Png)
                .unwrap()
                .to_rgb8();
            assert_eq!(back.dimensions(), (w, h));
            assert!(back.as_raw() == &data, "{w}x{h}");
            // the same rows in pieces of 1 to 3 rows, and in pieces that split rows
            let row = w as usize * 3;
            for piece in [row, 2 * row + row / 2 + 1, 3 * row, 1] {
                let mut png = PngRows::new(w, h).unwrap();
                for p in data.chunks(piece) {
                    png.push(p).unwrap();
                }
                assert!(
                    png.finish().unwrap() == whole,
                    "{w}x{h} in pieces of {piece}"
                );
            }
        }
    }

    #[test]
    fn a_png_short_of_rows_or_given_too_many_is_an_error() {
        let mut rng = Rng(5);
        let data = image(4, 3, &mut rng);
        let mut png = PngRows::new(4, 3).unwrap();
        png.push(&data[..24]).unwrap();
        assert!(png.finish().is_err(), "one row missing");
        let mut png = PngRows::new(4, 3).unwrap();
        assert!(
            png.push(&[data.clone(), data].concat()).is_err(),
            "three rows too many"
        );
        assert!(PngRows::new(0, 3).is_err(), "no columns");
    }
}
