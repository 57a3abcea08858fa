//! The streaming frame loop both tracers run: the sample region is cut into bands of
//! [`BAND_ROWS`] rows (aligned to the image's rows, so a band is the same wherever the window
//! lies); worker threads take bands in order, trace each with the tracer's closure, and the
//! thread that completes the last band an output band's filter support needs filters it at
//! once. A band's samples are freed when every output band that reads them is done, so the
//! samples held stay a few bands per thread, whatever the image size. When several threads
//! render, the last band of each is traced in [`TAIL_PIECES`] column pieces, joined once all
//! are in, so that the threads finish close together.
//!
//! ```text
//! worker: k = next band (or piece, joined to its band when the last piece is in) --trace--> samples k
//!         --> output bands m whose bands lo(m)..=hi(m) are all in:
//!         filter m --> its rows of the output --> progress(those rows, final pixels and all);
//!         free the bands no unfiltered output band needs
//! ```
//!
//! The progress hook sees each row once, with the pixels the frame will hold: the command line
//! makes its 8-bit images from them while the render runs (`output::StreamedImage`).
//!
//! The bytes do not depend on the thread count or on which thread did what: a band's samples
//! are a function of the band (each sample's of its pixel and index alone, so a band joined
//! from pieces holds what the whole band would), and an output pixel a function of the samples
//! (one fixed summation order, [`super::filter_rows`]).

use std::collections::BTreeMap;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, PoisonError};

use super::{FilmSpec, SampleBlock, SampleRows, filter_rows};
use crate::error::Result;
use crate::fill::filled;
use crate::math::Vec3;
use crate::options::{FinishedRows, Progress, RowPixels, Window};

/// Rows per band of samples: the unit of parallel work and of streaming.
pub const BAND_ROWS: u32 = 8;

/// Column pieces each of the last bands is traced in when several threads render (the last
/// band of each thread; none on one thread). Whole, the last band kept one thread waiting for
/// the other's for about half a band: 0.64–0.84 ms of the course bunny's 2-thread frame, whose
/// bands take 1.8 ms; in 4 pieces 0.31 ms, in 8 no less (PERF.md, sitting 57). A piece starts
/// at a multiple of 4 columns, where the packet tracer's 4x2 tiles start.
pub const TAIL_PIECES: u32 = 4;

/// The pixels of the window, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct FilmOutput {
    /// Where the pixels lie in the full image, and its size.
    pub window: Window,
    pub image_width: u32,
    pub image_height: u32,
    /// Linear RGB per pixel, filtered; empty when the film keeps no pixels
    /// ([`FilmSpec::keep_pixels`]).
    pub color: Vec<Vec3>,
    /// Per pixel, the distance to the hit of its sample nearest the centre (`+inf` for none);
    /// empty unless asked for (and pixels kept).
    pub depth: Vec<f32>,
    /// Per pixel, the unit normal at that hit (zero for none); empty like `depth`.
    pub normal: Vec<Vec3>,
    /// Every sample's colour, pixel by pixel (`spp` each, in sample order); empty unless asked.
    pub samples: Vec<Vec3>,
}

/// One output band's share of the output.
struct OutRows<'o> {
    color: &'o mut [Vec3],
    depth: &'o mut [f32],
    normal: &'o mut [Vec3],
    samples: &'o mut [Vec3],
}

/// Which bands exist and which output band reads which bands of samples.
struct Plan {
    spec: FilmSpec,
    region: Window,
    r: u32,
    /// Sample bands are numbered by `y / BAND_ROWS`: `first..=last`.
    first: u32,
    last: u32,
    /// Output bands, likewise: `out_first..=out_last`.
    out_first: u32,
    out_last: u32,
}

impl Plan {
    fn new(spec: &FilmSpec) -> Plan {
        let region = spec.region();
        let w = spec.window;
        Plan {
            spec: *spec,
            region,
            r: spec.filter.support_radius(),
            first: region.y0 / BAND_ROWS,
            last: (region.y1 - 1) / BAND_ROWS,
            out_first: w.y0 / BAND_ROWS,
            out_last: (w.y1 - 1) / BAND_ROWS,
        }
    }

    /// The rows of sample band `k`.
    fn sample_rows(&self, k: u32) -> Range<u32> {
        (k * BAND_ROWS).max(self.region.y0)..((k + 1) * BAND_ROWS).min(self.region.y1)
    }

    /// The rows of output band `m`.
    fn output_rows(&self, m: u32) -> Range<u32> {
        let w = self.spec.window;
        (m * BAND_ROWS).max(w.y0)..((m + 1) * BAND_ROWS).min(w.y1)
    }

    /// The sample bands output band `m` reads.
    fn needs(&self, m: u32) -> Range<u32> {
        let rows = self.output_rows(m);
        let top = rows.start.saturating_sub(self.r).max(self.region.y0);
        let bottom = (rows.end - 1)
            .saturating_add(self.r)
            .min(self.region.y1 - 1);
        top / BAND_ROWS..bottom / BAND_ROWS + 1
    }

    /// The work of the frame in the order the workers take it: the bands top to bottom, whole
    /// but for the last `threads` of them when `threads` > 1, each of which comes as its column
    /// pieces, left to right.
    fn work(&self, threads: usize) -> Vec<Work> {
        let (x0, width) = (self.region.x0, self.region.width());
        let split_from = match threads {
            0 | 1 => self.last + 1,
            n => self.last.saturating_sub(n as u32 - 1).max(self.first),
        };
        let tail_piece = width.div_ceil(TAIL_PIECES).next_multiple_of(4);
        let mut work = Vec::new();
        for band in self.first..=self.last {
            // a whole band is its one piece
            let piece = if band < split_from { width } else { tail_piece };
            let of = width.div_ceil(piece);
            work.extend((0..of).map(|p| Work {
                band,
                x0: x0 + p * piece,
                width: piece.min(width - p * piece),
                of,
            }));
        }
        work
    }

    /// The output bands that read sample band `k`.
    fn readers(&self, k: u32) -> impl Iterator<Item = u32> + '_ {
        let reach = self.r / BAND_ROWS + 1;
        let lo = k.saturating_sub(reach).max(self.out_first);
        let hi = k.saturating_add(reach).min(self.out_last);
        (lo..=hi).filter(move |&m| self.needs(m).contains(&k))
    }
}

/// One unit of the workers' work: columns `x0..x0 + width` of the sample region's rows of
/// band `band`, one of the `of` pieces of the band (1: the whole band).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Work {
    band: u32,
    x0: u32,
    width: u32,
    of: u32,
}

/// What the workers share.
struct Shared<'o, T> {
    /// Traced sample bands still needed.
    bands: BTreeMap<u32, Arc<SampleBlock>>,
    /// The pieces traced so far of bands that come in pieces, by band.
    pieces: BTreeMap<u32, Vec<SampleBlock>>,
    /// Output bands (by `m - out_first`) not yet claimed, and their rows of the output.
    outputs: Vec<Option<OutRows<'o>>>,
    /// Output bands filtered.
    filtered: Vec<bool>,
    /// What each unit of work's trace returned (by its place in the work).
    results: Vec<Option<T>>,
    error: Option<crate::error::Error>,
}

/// Renders the window of `spec`: `trace` fills the colours (and, when kept, depths and
/// normals) of each band's [`SampleBlock`] (or of each column piece of one), with per-thread
/// state made by `init`; the film filters them. Returns the output and what `trace` returned
/// for each block it was handed, bands in order, a band's pieces left to right. Runs on the
/// current rayon pool, one worker per thread; the pieces depend on that pool's size, the
/// output does not.
pub fn render_film<S, T, I, F>(
    spec: &FilmSpec,
    progress: Progress,
    init: I,
    trace: F,
) -> Result<(FilmOutput, Vec<T>)>
where
    T: Send,
    I: Fn() -> S + Sync,
    F: Fn(&mut S, &mut SampleBlock) -> Result<T> + Sync,
{
    let plan = Plan::new(spec);
    let w = spec.window;
    let (ww, spp) = (w.width() as usize, spec.sampler.count as usize);
    let pixels = w.pixels() as usize;
    let kept_pixels = if spec.keep_pixels { pixels } else { 0 };
    let aux = if spec.depth_normal { kept_pixels } else { 0 };
    let kept = if spec.keep_samples { pixels * spp } else { 0 };
    let mut out = FilmOutput {
        window: w,
        image_width: spec.image_width,
        image_height: spec.image_height,
        color: filled(kept_pixels, Vec3::ZERO),
        depth: filled(aux, f32::INFINITY),
        normal: filled(aux, Vec3::ZERO),
        samples: filled(kept, Vec3::ZERO),
    };
    let outputs = split_rows(&plan, &mut out, ww, spp);
    let work = plan.work(rayon::current_num_threads());
    let shared = Mutex::new(Shared {
        bands: BTreeMap::new(),
        pieces: BTreeMap::new(),
        filtered: vec![false; outputs.len()],
        outputs,
        results: work.iter().map(|_| None).collect(),
        error: None,
    });
    let next = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    let worker = || {
        let mut state = init();
        while !stop.load(Ordering::Relaxed) {
            let i = next.fetch_add(1, Ordering::Relaxed);
            let Some(&Work {
                band: k,
                x0,
                width,
                of,
            }) = work.get(i)
            else {
                break;
            };
            let rows = plan.sample_rows(k);
            let mut block = SampleBlock::new(
                x0,
                rows.start,
                width,
                rows.end - rows.start,
                spec.image_width,
                spec.image_height,
                &spec.sampler,
                spec.depth_normal,
            );
            let traced = trace(&mut state, &mut block);
            let ready = {
                let mut sh = shared.lock().unwrap_or_else(PoisonError::into_inner);
                match traced {
                    Ok(t) => sh.results[i] = Some(t),
                    Err(e) => {
                        sh.error.get_or_insert(e);
                        stop.store(true, Ordering::Relaxed);
                        break;
                    }
                }
                let block = if of == 1 {
                    block
                } else {
                    let pieces = sh.pieces.entry(k).or_default();
                    pieces.push(block);
                    if pieces.len() < of as usize {
                        continue;
                    }
                    let pieces = sh.pieces.remove(&k).expect("the band's pieces");
                    SampleBlock::join_columns(pieces)
                };
                sh.bands.insert(k, Arc::new(block));
                claim_ready(&plan, &mut sh, k)
            };
            for (m, bands, rows) in ready {
                // Without the frame's pixels, the output band's own, for the hook to see.
                let (mut color, mut depth, mut normal);
                let mut rows = if spec.keep_pixels {
                    rows
                } else {
                    let n = plan.output_rows(m).len() * ww;
                    let aux = if spec.depth_normal { n } else { 0 };
                    (color, depth, normal) =
                        (vec![Vec3::ZERO; n], vec![0.0; aux], vec![Vec3::ZERO; aux]);
                    OutRows {
                        color: &mut color,
                        depth: &mut depth,
                        normal: &mut normal,
                        samples: rows.samples,
                    }
                };
                filter_band(&plan, m, &bands, &mut rows);
                let out_rows = plan.output_rows(m);
                let y0 = spec.window.y0;
                progress(&FinishedRows {
                    count: out_rows.len() as u32,
                    pixels: Some(RowPixels {
                        rows: out_rows.start - y0..out_rows.end - y0,
                        color: rows.color,
                        depth: rows.depth,
                        normal: rows.normal,
                    }),
                });
                let mut sh = shared.lock().unwrap_or_else(PoisonError::into_inner);
                sh.filtered[(m - plan.out_first) as usize] = true;
                release(&plan, &mut sh, plan.needs(m));
            }
        }
    };
    rayon::scope(|s| {
        for _ in 0..rayon::current_num_threads() {
            s.spawn(|_| worker());
        }
    });
    let sh = shared.into_inner().unwrap_or_else(PoisonError::into_inner);
    if let Some(e) = sh.error {
        return Err(e);
    }
    let results = sh
        .results
        .into_iter()
        .map(|t| t.expect("every block was traced"))
        .collect();
    Ok((out, results))
}

/// Cuts the output into one share per output band.
fn split_rows<'o>(
    plan: &Plan,
    out: &'o mut FilmOutput,
    ww: usize,
    spp: usize,
) -> Vec<Option<OutRows<'o>>> {
    let (pixels, aux, kept) = (
        !out.color.is_empty(),
        !out.depth.is_empty(),
        !out.samples.is_empty(),
    );
    let mut color = out.color.as_mut_slice();
    let mut depth = out.depth.as_mut_slice();
    let mut normal = out.normal.as_mut_slice();
    let mut samples = out.samples.as_mut_slice();
    let mut shares = Vec::new();
    for m in plan.out_first..=plan.out_last {
        let n = plan.output_rows(m).len() * ww;
        let (a, k) = (if aux { n } else { 0 }, if kept { n * spp } else { 0 });
        let c;
        (c, color) = std::mem::take(&mut color).split_at_mut(if pixels { n } else { 0 });
        let d;
        (d, depth) = std::mem::take(&mut depth).split_at_mut(a);
        let nm;
        (nm, normal) = std::mem::take(&mut normal).split_at_mut(a);
        let s;
        (s, samples) = std::mem::take(&mut samples).split_at_mut(k);
        shares.push(Some(OutRows {
            color: c,
            depth: d,
            normal: nm,
            samples: s,
        }));
    }
    shares
}

/// The output bands that sample band `k` completes: claims them and hands out their bands.
type Ready<'o> = Vec<(u32, Vec<Arc<SampleBlock>>, OutRows<'o>)>;

fn claim_ready<'o, T>(plan: &Plan, sh: &mut Shared<'o, T>, k: u32) -> Ready<'o> {
    let mut ready = Vec::new();
    for m in plan.readers(k) {
        let slot = (m - plan.out_first) as usize;
        if sh.outputs[slot].is_none() || !plan.needs(m).all(|b| sh.bands.contains_key(&b)) {
            continue;
        }
        let bands = plan.needs(m).map(|b| Arc::clone(&sh.bands[&b])).collect();
        let rows = sh.outputs[slot].take().expect("unclaimed");
        ready.push((m, bands, rows));
    }
    ready
}

/// Frees the bands of `range` that no unfiltered output band reads any more.
fn release<T>(plan: &Plan, sh: &mut Shared<'_, T>, range: Range<u32>) {
    for b in range {
        if plan
            .readers(b)
            .all(|m| sh.filtered[(m - plan.out_first) as usize])
        {
            sh.bands.remove(&b);
        }
    }
}

/// Filters output band `m` from its sample bands into its rows of the output.
fn filter_band(plan: &Plan, m: u32, bands: &[Arc<SampleBlock>], out: &mut OutRows<'_>) {
    let spec = &plan.spec;
    let (w, region) = (spec.window, plan.region);
    let spp = spec.sampler.count as usize;
    let row_len = region.width() as usize * spp;
    let mut rows = SampleRows {
        y0: bands[0].y0,
        x0: region.x0,
        spp: spp as u32,
        rows: Vec::new(),
    };
    for band in bands {
        for r in 0..band.rows as usize {
            let span = r * row_len..(r + 1) * row_len;
            rows.rows
                .push((&band.color[span.clone()], &band.offsets[span]));
        }
    }
    let ww = w.width() as usize;
    let out_rows = plan.output_rows(m);
    filter_rows(
        &spec.filter,
        &rows,
        w.x0..w.x1,
        out_rows.clone(),
        spec.image_width,
        spec.image_height,
        out.color,
    );
    for (ry, y) in out_rows.enumerate() {
        let band = bands
            .iter()
            .find(|b| (b.y0..b.y0 + b.rows).contains(&y))
            .expect("the band of an output row");
        let brow = (y - band.y0) as usize * region.width() as usize;
        for (rx, x) in (w.x0..w.x1).enumerate() {
            let (i, p) = (ry * ww + rx, brow + (x - region.x0) as usize);
            if !out.depth.is_empty() {
                out.depth[i] = band.depth[p];
                out.normal[i] = band.normal[p];
            }
            if !out.samples.is_empty() {
                out.samples[i * spp..(i + 1) * spp]
                    .copy_from_slice(&band.color[p * spp..(p + 1) * spp]);
            }
        }
    }
}
