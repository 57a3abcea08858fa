//! 8-bit images written while the render runs, from the rows the film finishes ([`RowPixels`],
//! through the render's progress hook), so that little of their writing is left after the
//! render. Two ways, by format:
//!
//! - A TGA or PPM stores its rows uncompressed at fixed places: the rows are converted at once
//!   and gathered into chunks of about [`CHUNK_BYTES`]; each chunk is written when complete, and
//!   the disk starts taking it. The image's durable write after the render is then its last
//!   chunk and a short `fsync`, not the whole file: for a 10-megapixel TGA, 7–10 ms instead of
//!   190–240 (PERF.md, sitting 52). The file has no name until [`super::write_files`] gives it
//!   one, so an interrupted render leaves nothing in the folder; the image still appears by a
//!   rename, whole, or not at all. Linux only (an unnamed file, `O_TMPFILE`).
//! - A PNG is one compressed stream of its rows in order: each band's rows are converted at
//!   once and wait until the rows above them are in; then the thread that brought the missing
//!   rows compresses every row that can go ([`PngRows`]), while the other threads trace. The
//!   file's bytes are handed over after the render and written as any file is; they are those
//!   of the PNG encoded from the finished frame ([`super::png_rows`]).
//!
//! A TGA or PPM off Linux, a float format, and an image whose rows did not all arrive are
//! encoded after the render instead. For the showcase's 1280x960 PNG, the write after the render
//! went from 9–12 ms to about 2 (PERF.md, sitting 54).
//!
//! ```text
//! film --RowPixels--> StreamedImage::rows: kind_to_bytes -->
//!     TGA, PPM: store_row --> its chunk; a chunk complete --> pwrite + writeback (sync_file_range)
//!     PNG: waiting by first row --> the rows that can go, in order --> PngRows (filter, compress)
//! after the render: into_content (every row in?) --> write_files: fsync, link or write, rename
//! ```

use std::collections::BTreeMap;
use std::fs::File;
use std::ops::Range;
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::{Mutex, PoisonError};

use super::png_rows::PngRows;
use super::rgb8::{Pixels, fixed_header, kind_to_bytes, store_row, stored_row};
use super::{Content, Format, ImageKind};
use crate::options::RowPixels;

/// File bytes written at once, about: rows are gathered into chunks of this size, as one write
/// and one writeback request for each band of 8 rows cost an 800x800 frame more than its whole
/// durable write after the render (PERF.md, sitting 52).
const CHUNK_BYTES: usize = 1 << 18;

/// An image being written as the render finishes its rows.
pub struct StreamedImage {
    kind: ImageKind,
    width: u32,
    height: u32,
    how: How,
    /// A write failed, or rows came without the pixels this image needs, or twice: the image
    /// is then encoded after the render instead.
    failed: AtomicBool,
}

/// How the rows become the file, by format.
enum How {
    /// TGA, PPM: rows stored in place in an unnamed file, chunk by chunk.
    InPlace(InPlace),
    /// PNG: rows compressed in order, into bytes handed over after the render (boxed: the
    /// encoder's state is large).
    Compressed(Box<Compressed>),
}

/// A TGA or PPM image in an unnamed file in its folder.
struct InPlace {
    file: File,
    format: Format,
    header: u64,
    /// Rows per chunk: chunk `c` holds the window's rows `c * chunk_rows..`.
    chunk_rows: u32,
    /// Each chunk's stored bytes while its rows come in, and how many have.
    chunks: Vec<Mutex<Chunk>>,
}

/// One chunk's rows as the file stores them, gathered until all are in.
#[derive(Default)]
struct Chunk {
    stored: Vec<u8>,
    /// Rows taken in; the chunk is written when they are all its rows (the film hands each row
    /// over once: more means a fault, and the image is then encoded after the render).
    rows: u32,
}

/// A PNG compressed as its rows come.
struct Compressed {
    /// Converted rows not compressed yet, by their first row: each band's RGB bytes.
    waiting: Mutex<BTreeMap<u32, Vec<u8>>>,
    /// The encoder, held by the one thread compressing.
    encoder: Mutex<PngRows>,
    /// The first row not compressed yet (written under `encoder`).
    next: AtomicU32,
}

impl StreamedImage {
    /// An image of `kind` for `path`, `width` x `height` pixels, written as its rows are
    /// finished; `None` where that cannot be (a float format; a TGA or PPM where there are no
    /// unnamed files: not Linux, or not in that folder): the image is then encoded after the
    /// render.
    pub fn create(path: &Path, kind: ImageKind, width: u32, height: u32) -> Option<StreamedImage> {
        StreamedImage::chunked(path, kind, width, height, CHUNK_BYTES)
    }

    /// [`create`](Self::create), with chunks of about `chunk_bytes` (TGA, PPM).
    fn chunked(
        path: &Path,
        kind: ImageKind,
        width: u32,
        height: u32,
        chunk_bytes: usize,
    ) -> Option<StreamedImage> {
        let format = Format::for_path(path).ok()?;
        let how = if format == Format::Png {
            How::Compressed(Box::new(Compressed {
                waiting: Mutex::default(),
                encoder: Mutex::new(PngRows::new(width, height).ok()?),
                next: AtomicU32::new(0),
            }))
        } else {
            let header = fixed_header(format, width, height)?;
            let file = unnamed_file(path)?;
            write_at(&file, &header, 0).ok()?;
            let chunk_rows =
                (chunk_bytes / (width as usize * 3).max(1)).clamp(1, height.max(1) as usize);
            let chunks = (height as usize).div_ceil(chunk_rows);
            How::InPlace(InPlace {
                file,
                format,
                header: header.len() as u64,
                chunk_rows: chunk_rows as u32,
                chunks: (0..chunks).map(|_| Mutex::default()).collect(),
            })
        };
        Some(StreamedImage {
            kind,
            width,
            height,
            how,
            failed: AtomicBool::new(false),
        })
    }

    /// Takes the finished rows `px` (rows of the window, as wide as it): writes each chunk of
    /// a TGA or PPM they complete, starting its writeback; compresses the rows of a PNG that
    /// can go. Called from the render's worker threads, once for each band of rows.
    pub fn rows(&self, px: &RowPixels<'_>) {
        if self.failed.load(Ordering::Relaxed) {
            return;
        }
        let (w, n) = (self.width as usize, px.rows.len());
        let needs_aux = !matches!(self.kind, ImageKind::Color);
        let sized = |len: usize| len == w * n;
        if px.rows.end > self.height
            || !sized(px.color.len())
            || needs_aux && !(sized(px.depth.len()) && sized(px.normal.len()))
        {
            self.failed.store(true, Ordering::Relaxed);
            return;
        }
        let pixels = Pixels {
            color: px.color,
            depth: px.depth,
            normal: px.normal,
        };
        let mut rgb = vec![0u8; n * w * 3];
        kind_to_bytes(self.kind, pixels, 0, &mut rgb);
        let written = match &self.how {
            How::InPlace(img) => img.rows(px.rows.clone(), &rgb, w * 3, self.height),
            How::Compressed(img) => img.rows(px.rows.start, rgb, w * 3),
        };
        if !written {
            self.failed.store(true, Ordering::Relaxed);
        }
    }

    /// True if every row was written (or compressed) and nothing failed.
    pub fn complete(&self) -> bool {
        !self.failed.load(Ordering::Relaxed)
            && match &self.how {
                How::InPlace(img) => img.chunks.iter().enumerate().all(|(c, chunk)| {
                    let chunk = chunk.lock().unwrap_or_else(PoisonError::into_inner);
                    chunk.rows == img.chunk_range(c as u32, self.height).len() as u32
                }),
                How::Compressed(img) => img.next.load(Ordering::Acquire) == self.height,
            }
    }

    /// What the file holds, if [`complete`](Self::complete): the unnamed file of a TGA or PPM,
    /// the bytes of a PNG. `None` means the image must be encoded from the frame instead.
    pub fn into_content(self) -> Option<Content> {
        if !self.complete() {
            return None;
        }
        match self.how {
            How::InPlace(img) => Some(Content::Written(img.file)),
            How::Compressed(img) => {
                let encoder = img.encoder.into_inner().ok()?;
                encoder.finish().ok().map(Content::Bytes)
            }
        }
    }
}

impl InPlace {
    /// Stores the image rows `rows` (their RGB bytes `rgb`, `row` bytes each, of an image
    /// `height` rows high) in their chunks and writes the chunks they complete; false if a
    /// write failed.
    fn rows(&self, rows: Range<u32>, rgb: &[u8], row: usize, height: u32) -> bool {
        let mut y = rows.start;
        while y < rows.end {
            let c = y / self.chunk_rows;
            let chunk_rows = self.chunk_range(c, height);
            let end = chunk_rows.end.min(rows.end);
            let mut chunk = self.chunks[c as usize]
                .lock()
                .unwrap_or_else(PoisonError::into_inner);
            if chunk.stored.is_empty() {
                chunk.stored = vec![0u8; chunk_rows.len() * row];
            }
            // The chunk's rows are consecutive in the file, in one order or the other.
            let first = self.first_stored(chunk_rows.clone(), height);
            for y in y..end {
                let at = (stored_row(self.format, height, y) - first) as usize * row;
                let src = (y - rows.start) as usize * row;
                store_row(
                    self.format,
                    &rgb[src..src + row],
                    &mut chunk.stored[at..at + row],
                );
            }
            chunk.rows += end - y;
            if chunk.rows == chunk_rows.len() as u32 {
                let stored = std::mem::take(&mut chunk.stored);
                drop(chunk);
                let offset = self.header + first as u64 * row as u64;
                if write_at(&self.file, &stored, offset).is_err() {
                    return false;
                }
                start_writeback(&self.file, offset, stored.len() as u64);
            }
            y = end;
        }
        true
    }

    /// The window's rows in chunk `c` of an image `height` rows high.
    fn chunk_range(&self, c: u32, height: u32) -> Range<u32> {
        c * self.chunk_rows..((c + 1) * self.chunk_rows).min(height)
    }

    /// The first stored row (in file order) of the image rows `rows`.
    fn first_stored(&self, rows: Range<u32>, height: u32) -> u32 {
        let (a, b) = (rows.start, rows.end - 1);
        stored_row(self.format, height, a).min(stored_row(self.format, height, b))
    }
}

impl Compressed {
    /// Puts the rows from `first` on (their RGB bytes `rgb`, `row` bytes each) in waiting, then
    /// compresses every row that can go, unless another thread is compressing: that one then
    /// takes them too, as it looks again after letting the encoder go. False if the rows came
    /// before (a fault) or the encoder failed.
    fn rows(&self, first: u32, rgb: Vec<u8>, row: usize) -> bool {
        {
            let mut waiting = self.waiting.lock().unwrap_or_else(PoisonError::into_inner);
            if first < self.next.load(Ordering::Acquire) || waiting.insert(first, rgb).is_some() {
                return false;
            }
        }
        loop {
            let Ok(mut encoder) = self.encoder.try_lock() else {
                // Held (its holder looks again after letting it go), or poisoned: then
                // `into_content` finds it so, and the image is encoded after the render.
                return true;
            };
            loop {
                let next = self.next.load(Ordering::Relaxed);
                let band = self
                    .waiting
                    .lock()
                    .unwrap_or_else(PoisonError::into_inner)
                    .remove(&next);
                let Some(band) = band else { break };
                if encoder.push(&band).is_err() {
                    return false;
                }
                self.next
                    .store(next + (band.len() / row.max(1)) as u32, Ordering::Release);
            }
            drop(encoder);
            // Rows put in waiting since the last look, while the encoder was held, are this
            // thread's to compress.
            let next = self.next.load(Ordering::Acquire);
            let waiting = self.waiting.lock().unwrap_or_else(PoisonError::into_inner);
            if !waiting.contains_key(&next) {
                return true;
            }
        }
    }
}

/// An unnamed file in `path`'s folder, or `None` where the system has none to give.
#[cfg(target_os = "linux")]
fn unnamed_file(path: &Path) -> Option<File> {
    use std::os::unix::fs::OpenOptionsExt;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    // Readable too, so the bytes can be copied where it cannot be linked
    std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .custom_flags(libc::O_TMPFILE)
        .mode(0o666)
        .open(dir)
        .ok()
}

#[cfg(not(target_os = "linux"))]
fn unnamed_file(_: &Path) -> Option<File> {
    None
}

/// Gives the unnamed `file` the name `name` (a new name in the file's own folder).
#[cfg(target_os = "linux")]
pub(super) fn link_unnamed(file: &File, name: &Path) -> std::io::Result<()> {
    use std::ffi::CString;
    use std::os::unix::ffi::OsStrExt;
    use std::os::unix::io::AsRawFd;
    let proc = CString::new(format!("/proc/self/fd/{}", file.as_raw_fd()))?;
    let name = CString::new(name.as_os_str().as_bytes())?;
    // SAFETY: both are NUL-terminated paths that outlive the call.
    let r = unsafe {
        libc::linkat(
            libc::AT_FDCWD,
            proc.as_ptr(),
            libc::AT_FDCWD,
            name.as_ptr(),
            libc::AT_SYMLINK_FOLLOW,
        )
    };
    if r == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}

#[cfg(not(target_os = "linux"))]
pub(super) fn link_unnamed(_: &File, _: &Path) -> std::io::Result<()> {
    Err(std::io::Error::from(std::io::ErrorKind::Unsupported))
}

#[cfg(unix)]
fn write_at(file: &File, bytes: &[u8], offset: u64) -> std::io::Result<()> {
    std::os::unix::fs::FileExt::write_all_at(file, bytes, offset)
}

#[cfg(not(unix))]
fn write_at(_: &File, _: &[u8], _: u64) -> std::io::Result<()> {
    Err(std::io::Error::from(std::io::ErrorKind::Unsupported))
}

/// Asks the kernel to start writing `len` bytes at `offset` to disk now, not waiting for them
/// (the `fsync` at the end then has little left to wait for).
#[cfg(target_os = "linux")]
fn start_writeback(file: &File, offset: u64, len: u64) {
    use std::os::unix::io::AsRawFd;
    // SAFETY: a plain system call on an open descriptor; a failure only loses the head start.
    unsafe {
        libc::sync_file_range(
            file.as_raw_fd(),
            offset as libc::off64_t,
            len as libc::off64_t,
            libc::SYNC_FILE_RANGE_WRITE,
        );
    }
}

#[cfg(not(target_os = "linux"))]
fn start_writeback(_: &File, _: u64, _: u64) {}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;
    use crate::frame::Frame;
    use crate::math::Vec3;
    use crate::output::rgb8::{encode_rgb8, frame_image};
    use crate::output::{Source, write_atomic_files};
    use crate::test_rng::Rng;

    /// A fresh folder for one test.
    fn folder(name: &str) -> std::path::PathBuf {
        let dir =
            std::env::temp_dir().join(format!("whitted-streamed-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// A `w` x `h` frame of colours, depths and normals a conversion can get wrong: NaN,
    /// infinities, values past 0 and 1.
    fn frame(w: u32, h: u32, rng: &mut Rng) -> Frame {
        let mut f = Frame::new(w, h);
        let value = |rng: &mut Rng| match rng.next() % 12 {
            0 => f32::NAN,
            1 => f32::INFINITY,
            2 => -1.5,
            3 => 7.0,
            _ => rng.range(0.0, 1.0),
        };
        for i in 0..(w * h) as usize {
            f.color[i] = Vec3::new(value(rng), value(rng), value(rng));
            f.depth[i] = if rng.next() % 4 == 0 {
                f32::INFINITY
            } else {
                2.0 + 6.0 * rng.range(0.0, 1.0)
            };
            f.normal[i] = Vec3::new(value(rng), -value(rng), value(rng));
        }
        f
    }

    /// The frame's rows cut into bands of 1 to 9 rows, handed over in a shuffled order.
    fn feed(image: &StreamedImage, f: &Frame, rng: &mut Rng, skip: Option<usize>, aux: bool) {
        let (w, h) = (f.width as usize, f.height);
        let mut bands = Vec::new();
        let mut y = 0;
        while y < h {
            let end = (y + 1 + rng.next() % 9).min(h);
            bands.push(y..end);
            y = end;
        }
        for i in (1..bands.len()).rev() {
            bands.swap(i, (rng.next() % (i as u32 + 1)) as usize);
        }
        for (k, rows) in bands.into_iter().enumerate() {
            if Some(k) == skip {
                continue;
            }
            let px = rows.start as usize * w..rows.end as usize * w;
            let (depth, normal) = if aux {
                (&f.depth[px.clone()], &f.normal[px.clone()])
            } else {
                (&[][..], &[][..])
            };
            image.rows(&RowPixels {
                rows,
                color: &f.color[px],
                depth,
                normal,
            });
        }
    }

    #[test]
    fn rows_in_any_order_and_any_chunks_give_the_bytes_encoded_from_the_frame() {
        let dir = folder("bytes");
        let mut rng = Rng(52);
        let kinds = [
            ImageKind::Color,
            ImageKind::Depth {
                near: 3.0,
                far: 7.0,
            },
            ImageKind::Normals,
        ];
        for (w, h) in [(1, 1), (5, 3), (17, 40), (64, 9)] {
            let f = frame(w, h, &mut rng);
            for format in [Format::Tga, Format::Ppm, Format::Png] {
                for kind in kinds {
                    // chunks of one row, a few rows, rows not dividing the image, the whole image
                    for chunk_bytes in [
                        1,
                        3 * w as usize * 4,
                        3 * w as usize * 7 + 5,
                        usize::MAX / 2,
                    ] {
                        let path = dir.join(format!("img.{}", format.extension()));
                        let image = StreamedImage::chunked(&path, kind, w, h, chunk_bytes).unwrap();
                        feed(&image, &f, &mut rng, None, true);
                        let content = image.into_content().expect("every row was written");
                        write_atomic_files(&[(&path, content.source())], "write image").unwrap();
                        let want = frame_image(&f, kind);
                        let want = encode_rgb8(w, h, &want.data, format).unwrap();
                        let what =
                            format!("{w}x{h} {format:?} {kind:?} chunks of {chunk_bytes} bytes");
                        assert!(std::fs::read(&path).unwrap() == want, "{what}");
                    }
                }
            }
        }
    }

    #[test]
    fn png_rows_from_several_threads_at_once_give_the_bytes_encoded_from_the_frame() {
        let mut rng = Rng(77);
        let (w, h) = (256, 48);
        let f = frame(w, h, &mut rng);
        let want = encode_rgb8(w, h, &frame_image(&f, ImageKind::Color).data, Format::Png).unwrap();
        let path = folder("threads").join("img.png");
        // Six bands of 8 rows, one to a thread, all six started at once, so that they meet at
        // the encoder: rows whose thread finds it held are compressed by the thread holding it.
        for round in 0..200 {
            let mut order: Vec<u32> = (0..6).collect();
            for i in (1..order.len()).rev() {
                order.swap(i, (rng.next() % (i as u32 + 1)) as usize);
            }
            let image = StreamedImage::create(&path, ImageKind::Color, w, h).unwrap();
            let start = std::sync::Barrier::new(order.len());
            std::thread::scope(|s| {
                for &band in &order {
                    let (image, f, start) = (&image, &f, &start);
                    s.spawn(move || {
                        let rows = band * 8..band * 8 + 8;
                        let px = rows.start as usize * w as usize..rows.end as usize * w as usize;
                        start.wait();
                        image.rows(&RowPixels {
                            rows,
                            color: &f.color[px],
                            depth: &[],
                            normal: &[],
                        });
                    });
                }
            });
            let Some(Content::Bytes(got)) = image.into_content() else {
                panic!("round {round} (bands in the order {order:?}): rows left uncompressed");
            };
            assert!(got == want, "round {round}");
        }
    }

    #[test]
    fn an_image_missing_rows_or_their_depths_is_not_complete() {
        let dir = folder("incomplete");
        let mut rng = Rng(7);
        let f = frame(9, 30, &mut rng);
        let path = dir.join("img.tga");
        // one band never came
        let image = StreamedImage::chunked(&path, ImageKind::Color, 9, 30, 100).unwrap();
        feed(&image, &f, &mut rng, Some(0), true);
        assert!(!image.complete());
        assert!(image.into_content().is_none());
        // a depth image given rows without depths
        let image = StreamedImage::chunked(
            &path,
            ImageKind::Depth {
                near: 1.0,
                far: 2.0,
            },
            9,
            30,
            100,
        )
        .unwrap();
        feed(&image, &f, &mut rng, None, false);
        assert!(image.into_content().is_none());
        // a colour image needs no depths
        let image = StreamedImage::chunked(&path, ImageKind::Color, 9, 30, 100).unwrap();
        feed(&image, &f, &mut rng, None, false);
        assert!(image.into_content().is_some());
        // a PNG missing one band (of shuffled bands: it may be the rows others wait for), or
        // given a row twice
        let png = dir.join("img.png");
        for skip in [0, 2] {
            let image = StreamedImage::create(&png, ImageKind::Color, 9, 30).unwrap();
            feed(&image, &f, &mut rng, Some(skip), false);
            assert!(!image.complete(), "band {skip} missing");
            assert!(image.into_content().is_none());
        }
        let image = StreamedImage::create(&png, ImageKind::Color, 9, 30).unwrap();
        feed(&image, &f, &mut rng, None, false);
        assert!(image.complete());
        image.rows(&RowPixels {
            rows: 0..1,
            color: &f.color[..9],
            depth: &[],
            normal: &[],
        });
        assert!(image.into_content().is_none(), "row 0 twice");
    }

    #[test]
    fn an_image_that_cannot_be_linked_is_copied_into_place() {
        let dir = folder("copied");
        let mut rng = Rng(11);
        let f = frame(6, 10, &mut rng);
        let path = dir.join("img.tga");
        // The temporary name already taken (by more bytes than the image): the link fails, and
        // the bytes are copied over it.
        std::fs::write(super::super::temp_path(&path), vec![7u8; 1000]).unwrap();
        let image = StreamedImage::chunked(&path, ImageKind::Color, 6, 10, 40).unwrap();
        feed(&image, &f, &mut rng, None, true);
        let Some(Content::Written(file)) = image.into_content() else {
            panic!("a TGA written whole is an unnamed file");
        };
        write_atomic_files(&[(&path, Source::Written(&file))], "write image").unwrap();
        let want =
            encode_rgb8(6, 10, &frame_image(&f, ImageKind::Color).data, Format::Tga).unwrap();
        assert!(std::fs::read(&path).unwrap() == want);
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
    }

    #[test]
    fn an_image_dropped_unfinished_leaves_nothing_in_its_folder() {
        let dir = folder("dropped");
        let mut rng = Rng(3);
        let f = frame(4, 20, &mut rng);
        let image =
            StreamedImage::chunked(&dir.join("img.ppm"), ImageKind::Color, 4, 20, 24).unwrap();
        feed(&image, &f, &mut rng, Some(1), true);
        drop(image);
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
    }

    #[test]
    fn the_float_formats_are_not_written_while_rendering_and_a_png_makes_no_file_before() {
        let dir = folder("formats");
        for ext in ["exr", "pfm", "hdr"] {
            let path = dir.join(format!("img.{ext}"));
            assert!(
                StreamedImage::create(&path, ImageKind::Color, 4, 4).is_none(),
                "{ext}"
            );
        }
        let png = StreamedImage::create(&dir.join("img.png"), ImageKind::Color, 4, 4);
        assert!(png.is_some());
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
    }
}
