//! 8-bit images written while the render runs. A TGA or PPM stores its rows uncompressed at
//! fixed places, so the rows the film finishes ([`RowPixels`], through the render's progress
//! hook) are converted at once and gathered into chunks of about [`CHUNK_BYTES`]; each chunk is
//! written when complete, and the disk starts taking it. The image's durable write after the
//! render is then its last chunk and a short `fsync`, not the whole file: for a 10-megapixel
//! TGA, 7–10 ms instead of 190–240 (PERF.md, sitting 52). The file has no name until
//! [`super::write_files`] gives it one, so an interrupted render leaves nothing in the folder;
//! the image still appears by a rename, whole, or not at all. Linux only (an unnamed file,
//! `O_TMPFILE`); elsewhere, and for PNG or the float formats, images are encoded after the
//! render as before, and so is an image whose rows did not all arrive.
//!
//! ```text
//! film --RowPixels--> StreamedImage::rows: kind_to_bytes, store_row --> its chunk
//!                     a chunk complete --> pwrite + writeback started (sync_file_range)
//! after the render: into_file (every chunk written?) --> write_files: fsync, link, rename
//! ```

use std::fs::File;
use std::ops::Range;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, PoisonError};

use super::rgb8::{Pixels, fixed_header, kind_to_bytes, store_row, stored_row};
use super::{Format, ImageKind};
use crate::options::RowPixels;

/// File bytes written at once, about: rows are gathered into chunks of this size, as one write
/// and one writeback request for each band of 8 rows cost an 800x800 frame more than its whole
/// durable write after the render (PERF.md, sitting 52).
const CHUNK_BYTES: usize = 1 << 18;

/// An image being written as the render finishes its rows: an unnamed file in its folder.
pub struct StreamedImage {
    file: File,
    kind: ImageKind,
    format: Format,
    width: u32,
    height: u32,
    header: u64,
    /// Rows per chunk: chunk `c` holds the window's rows `c * chunk_rows..`.
    chunk_rows: u32,
    /// Each chunk's stored bytes while its rows come in, and how many have.
    chunks: Vec<Mutex<Chunk>>,
    /// A write failed, or rows came without the pixels this image needs: the image is then
    /// encoded after the render instead.
    failed: AtomicBool,
}

/// One chunk's rows as the file stores them, gathered until all are in.
#[derive(Default)]
struct Chunk {
    stored: Vec<u8>,
    /// Rows taken in; the chunk is written when they are all its rows (the film hands each row
    /// over once: more means a fault, and the image is then encoded after the render).
    rows: u32,
}

impl StreamedImage {
    /// An image of `kind` for `path`, `width` x `height` pixels, written as its rows are
    /// finished; `None` where that cannot be (not a TGA or PPM, not Linux, no unnamed files in
    /// that folder): the image is then encoded after the render.
    pub fn create(path: &Path, kind: ImageKind, width: u32, height: u32) -> Option<StreamedImage> {
        StreamedImage::chunked(path, kind, width, height, CHUNK_BYTES)
    }

    /// [`create`](Self::create), with chunks of about `chunk_bytes`.
    fn chunked(
        path: &Path,
        kind: ImageKind,
        width: u32,
        height: u32,
        chunk_bytes: usize,
    ) -> Option<StreamedImage> {
        let format = Format::for_path(path).ok()?;
        let header = fixed_header(format, width, height)?;
        let file = unnamed_file(path)?;
        write_at(&file, &header, 0).ok()?;
        let chunk_rows =
            (chunk_bytes / (width as usize * 3).max(1)).clamp(1, height.max(1) as usize);
        let chunks = (height as usize).div_ceil(chunk_rows);
        Some(StreamedImage {
            file,
            kind,
            format,
            width,
            height,
            header: header.len() as u64,
            chunk_rows: chunk_rows as u32,
            chunks: (0..chunks).map(|_| Mutex::default()).collect(),
            failed: AtomicBool::new(false),
        })
    }

    /// Takes the finished rows `px` (rows of the window, as wide as it) into their chunks, and
    /// writes each chunk they complete, starting its writeback. Called from the render's worker
    /// threads, once for each band of rows.
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
        let row = w * 3;
        let mut rgb = vec![0u8; n * row];
        kind_to_bytes(self.kind, pixels, 0, &mut rgb);
        let mut y = px.rows.start;
        while y < px.rows.end {
            let c = y / self.chunk_rows;
            let rows = self.chunk_range(c);
            let end = rows.end.min(px.rows.end);
            let mut chunk = self.chunks[c as usize]
                .lock()
                .unwrap_or_else(PoisonError::into_inner);
            if chunk.stored.is_empty() {
                chunk.stored = vec![0u8; rows.len() * row];
            }
            // The chunk's rows are consecutive in the file, in one order or the other.
            let first = self.first_stored(rows.clone());
            for y in y..end {
                let at = (stored_row(self.format, self.height, y) - first) as usize * row;
                let src = (y - px.rows.start) as usize * row;
                store_row(
                    self.format,
                    &rgb[src..src + row],
                    &mut chunk.stored[at..at + row],
                );
            }
            chunk.rows += end - y;
            if chunk.rows == rows.len() as u32 {
                let stored = std::mem::take(&mut chunk.stored);
                drop(chunk);
                let offset = self.header + first as u64 * row as u64;
                if write_at(&self.file, &stored, offset).is_err() {
                    self.failed.store(true, Ordering::Relaxed);
                    return;
                }
                start_writeback(&self.file, offset, stored.len() as u64);
            }
            y = end;
        }
    }

    /// The window's rows in chunk `c`.
    fn chunk_range(&self, c: u32) -> Range<u32> {
        c * self.chunk_rows..((c + 1) * self.chunk_rows).min(self.height)
    }

    /// The first stored row (in file order) of the image rows `rows`.
    fn first_stored(&self, rows: Range<u32>) -> u32 {
        let (a, b) = (rows.start, rows.end - 1);
        stored_row(self.format, self.height, a).min(stored_row(self.format, self.height, b))
    }

    /// True if every row was written and no write failed.
    pub fn complete(&self) -> bool {
        !self.failed.load(Ordering::Relaxed)
            && self.chunks.iter().enumerate().all(|(c, chunk)| {
                let chunk = chunk.lock().unwrap_or_else(PoisonError::into_inner);
                chunk.rows == self.chunk_range(c as u32).len() as u32
            })
    }

    /// The file, if [`complete`](Self::complete); `None` means the image must be encoded from
    /// the frame instead.
    pub fn into_file(self) -> Option<File> {
        self.complete().then_some(self.file)
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
            for format in [Format::Tga, Format::Ppm] {
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
                        let file = image.into_file().expect("every row was written");
                        write_atomic_files(&[(&path, Source::Written(&file))], "write image")
                            .unwrap();
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
    fn an_image_missing_rows_or_their_depths_is_not_complete() {
        let dir = folder("incomplete");
        let mut rng = Rng(7);
        let f = frame(9, 30, &mut rng);
        let path = dir.join("img.tga");
        // one band never came
        let image = StreamedImage::chunked(&path, ImageKind::Color, 9, 30, 100).unwrap();
        feed(&image, &f, &mut rng, Some(0), true);
        assert!(!image.complete());
        assert!(image.into_file().is_none());
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
        assert!(image.into_file().is_none());
        // a colour image needs no depths
        let image = StreamedImage::chunked(&path, ImageKind::Color, 9, 30, 100).unwrap();
        feed(&image, &f, &mut rng, None, false);
        assert!(image.into_file().is_some());
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
        let file = image.into_file().unwrap();
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
    fn png_and_the_float_formats_are_not_written_while_rendering() {
        let dir = folder("formats");
        for ext in ["png", "exr", "pfm", "hdr"] {
            let path = dir.join(format!("img.{ext}"));
            assert!(
                StreamedImage::create(&path, ImageKind::Color, 4, 4).is_none(),
                "{ext}"
            );
        }
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
    }
}
