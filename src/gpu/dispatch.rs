//! How a render is cut into dispatches: bands of rows (tiles) and slices of samples, sized from
//! the measured cost of a pixel-sample so that a dispatch takes about `TARGET_DISPATCH_SECONDS`,
//! and kept within the driver's loop budget. Pure arithmetic, testable without a GPU.

/// GPU watchdogs kill long dispatches (~100 ms and up); dispatches aim well under that, so
/// that a band of the image 2x costlier than the one measured before it still stays under.
pub const TARGET_DISPATCH_SECONDS: f64 = 0.04;

/// Samples per pixel that a tile's dispatches grow to within the target time: tiles are sized
/// for this many, not one, because a dispatch reads and writes each pixel's accumulator once
/// (which lavapipe moves lane by lane), however many samples it takes.
pub const TILE_SAMPLES: u32 = 8;

/// Rows of the first tile, before any dispatch has been timed.
pub const PROBE_TILE_ROWS: u32 = 4;

/// Mesa's llvmpipe (lavapipe) silently ends any invocation after 65535 loop iterations in
/// total, across all its loops. Dispatches stay under this budget on every device (it costs
/// nothing elsewhere), and the kernel counts the samples it really took so that a cut loop is
/// an error, never a quietly wrong image.
pub const LOOP_ITERATION_BUDGET: u64 = 60_000;

/// What bounds one invocation's loop iterations per sample. Today's kernels have fixed-length
/// loops, so a bound is known before rendering; kernels with data-dependent loops (BVH
/// traversal, random walks) give their own bound, or measure it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LoopCost {
    /// Most loop iterations one sample may take, every loop's exit test counted.
    pub per_sample: u64,
}

impl LoopCost {
    /// Most samples one invocation may take in a dispatch within `LOOP_ITERATION_BUDGET`, or
    /// `None` when even one sample may exceed it.
    pub fn max_samples_per_dispatch(self) -> Option<u32> {
        (self.per_sample <= LOOP_ITERATION_BUDGET)
            .then(|| (LOOP_ITERATION_BUDGET / self.per_sample.max(1)).min(u32::MAX as u64) as u32)
    }
}

/// Fixed sizes that tests use to force tiling and slicing; renders normally leave them `None`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Tuning {
    /// Most pixels per tile [default: what one storage binding holds].
    pub max_tile_pixels: Option<u64>,
    /// Samples per dispatch [default: sized from measured dispatch time].
    pub samples_per_dispatch: Option<u32>,
}

/// Sizes tiles and slices as a render goes, from the time each dispatch took.
#[derive(Clone, Debug)]
pub struct DispatchSizer {
    width: u32,
    /// Most rows a tile may have (its accumulator must fit one storage binding).
    max_tile_rows: u32,
    /// Most samples per dispatch (the loop budget).
    max_slice: u32,
    tuning: Tuning,
    /// Seconds per pixel-sample, from the last dispatch.
    cost: Option<f64>,
    last_rows: u32,
}

impl DispatchSizer {
    /// For an image `width` pixels wide, tiles of at most `max_tile_pixels` (rounded down to
    /// whole rows, at least one) and dispatches of at most `max_slice` samples.
    pub fn new(width: u32, max_tile_pixels: u64, max_slice: u32, tuning: Tuning) -> Self {
        let max_tile_pixels = tuning
            .max_tile_pixels
            .map_or(max_tile_pixels, |t| t.min(max_tile_pixels));
        DispatchSizer {
            width,
            max_tile_rows: (max_tile_pixels / width.max(1) as u64).clamp(1, u32::MAX as u64) as u32,
            max_slice: max_slice.max(1),
            tuning,
            cost: None,
            last_rows: PROBE_TILE_ROWS / 2,
        }
    }

    /// Most rows any tile gets: what the accumulator buffer must hold.
    pub fn max_tile_rows(&self) -> u32 {
        self.max_tile_rows
    }

    /// Rows of the next tile, which starts at a row with `rows_left` rows below it: as tall as
    /// one dispatch of `TILE_SAMPLES` samples per pixel (or fewer, as the loop budget allows)
    /// may be, at most 2x the last tile (costs differ across the image: a band of sky is cheap,
    /// of glass not); before the first measurement, a short probe tile.
    pub fn next_tile_rows(&mut self, rows_left: u32) -> u32 {
        let rows = match self.cost {
            _ if self.tuning.max_tile_pixels.is_some() => self.max_tile_rows,
            None => PROBE_TILE_ROWS.min(self.max_tile_rows),
            Some(cost) => {
                let samples = TILE_SAMPLES.min(self.max_slice) as f64;
                let fit = TARGET_DISPATCH_SECONDS / (cost * self.width as f64 * samples);
                (fit.floor().min(u32::MAX as f64) as u32)
                    .clamp(1, self.max_tile_rows)
                    .min(self.last_rows.saturating_mul(2))
            }
        }
        .min(rows_left)
        .max(1);
        self.last_rows = rows;
        rows
    }

    /// Samples in a new tile's first dispatch: its cost is unknown, so one sample per pixel
    /// (which the tile height keeps well under the target).
    /// The most samples one dispatch may take (the loop budget on lavapipe).
    pub fn max_slice(&self) -> u32 {
        self.max_slice
    }

    pub fn first_slice(&self) -> u32 {
        self.tuning
            .samples_per_dispatch
            .unwrap_or(1)
            .clamp(1, self.max_slice)
    }

    /// Records that a dispatch of `samples` samples per pixel over `pixels` pixels took
    /// `seconds`; returns the samples for the next dispatch of the same tile (at most 2x).
    pub fn record(&mut self, samples: u32, pixels: u64, seconds: f64) -> u32 {
        let cost = seconds.max(1e-7) / (samples.max(1) as f64 * pixels.max(1) as f64);
        self.cost = Some(cost);
        if let Some(fixed) = self.tuning.samples_per_dispatch {
            return fixed.clamp(1, self.max_slice);
        }
        let ideal = TARGET_DISPATCH_SECONDS / (cost * pixels.max(1) as f64);
        (ideal.floor().min(u32::MAX as f64) as u32)
            .clamp(1, samples.saturating_mul(2).max(1))
            .min(self.max_slice)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A simulated device: every pixel-sample costs `cost` seconds.
    fn simulate(
        width: u32,
        height: u32,
        spp: u32,
        cost: f64,
        sizer: &mut DispatchSizer,
    ) -> Vec<(u32, u32, u32, f64)> {
        let mut dispatches = Vec::new();
        let mut y0 = 0;
        while y0 < height {
            let rows = sizer.next_tile_rows(height - y0);
            let mut slice = sizer.first_slice();
            let mut done = 0;
            while done < spp {
                let count = slice.min(spp - done);
                let pixels = rows as u64 * width as u64;
                let seconds = cost * count as f64 * pixels as f64;
                dispatches.push((y0, rows, count, seconds));
                done += count;
                slice = sizer.record(count, pixels, seconds);
            }
            y0 += rows;
        }
        dispatches
    }

    #[test]
    fn tiles_cover_the_image_once_and_every_pixel_gets_every_sample() {
        for (width, height, spp) in [(512, 512, 100), (1, 4096, 7), (4096, 1, 3), (17, 33, 1)] {
            let mut sizer = DispatchSizer::new(width, 1 << 20, 1000, Tuning::default());
            let dispatches = simulate(width, height, spp, 1e-7, &mut sizer);
            let mut rows_seen = vec![0u32; height as usize];
            for &(y0, rows, count, _) in &dispatches {
                for y in y0..y0 + rows {
                    rows_seen[y as usize] += count;
                }
            }
            assert!(rows_seen.iter().all(|&s| s == spp), "{width}x{height}");
        }
    }

    #[test]
    fn dispatches_settle_near_the_target_and_never_far_above_it() {
        for cost in [1e-9, 1e-7, 1e-5] {
            let mut sizer = DispatchSizer::new(512, 1 << 20, 60_000, Tuning::default());
            let dispatches = simulate(512, 512, 4096, cost, &mut sizer);
            let longest = dispatches.iter().map(|d| d.3).fold(0.0, f64::max);
            // The first probe may be short; nothing exceeds the target by more than rounding.
            assert!(
                longest <= TARGET_DISPATCH_SECONDS * 1.01,
                "cost {cost}: {longest}"
            );
            if cost >= 1e-7 {
                let settled = &dispatches[dispatches.len() / 2];
                assert!(
                    settled.3 >= TARGET_DISPATCH_SECONDS * 0.5,
                    "cost {cost}: {settled:?}"
                );
                // Tiles short enough that a dispatch takes several samples per pixel, so that
                // reading and writing the accumulators is paid once for them all.
                if cost <= 1e-7 {
                    assert!(settled.2 >= TILE_SAMPLES, "cost {cost}: {settled:?}");
                }
            }
        }
    }

    #[test]
    fn slices_and_tiles_grow_at_most_twofold_and_respect_the_loop_budget() {
        let mut sizer = DispatchSizer::new(64, 1 << 20, 37, Tuning::default());
        let dispatches = simulate(64, 4096, 500, 1e-10, &mut sizer);
        let mut last_rows = PROBE_TILE_ROWS / 2;
        for pair in dispatches.windows(2) {
            let ((y0, rows, count, _), (next_y0, next_rows, next_count, _)) = (pair[0], pair[1]);
            assert!(count <= 37 && next_count <= 37);
            if next_y0 == y0 {
                assert!(next_count <= 2 * count, "{pair:?}");
            } else {
                assert!(next_rows <= 2 * rows.max(last_rows), "{pair:?}");
                last_rows = rows;
            }
        }
    }

    #[test]
    fn tuning_fixes_tiles_and_slices() {
        let tuning = Tuning {
            max_tile_pixels: Some(64 * 3),
            samples_per_dispatch: Some(5),
        };
        let mut sizer = DispatchSizer::new(64, 1 << 20, 1000, tuning);
        let dispatches = simulate(64, 10, 12, 1e-6, &mut sizer);
        assert!(dispatches.iter().all(|d| d.1 <= 3 && d.2 <= 5));
        assert_eq!(dispatches.iter().filter(|d| d.0 == 0).count(), 3); // 5 + 5 + 2
    }

    #[test]
    fn the_loop_budget_bounds_samples_per_dispatch() {
        assert_eq!(
            LoopCost { per_sample: 60 }.max_samples_per_dispatch(),
            Some(1000)
        );
        assert_eq!(
            LoopCost { per_sample: 60_000 }.max_samples_per_dispatch(),
            Some(1)
        );
        assert_eq!(
            LoopCost { per_sample: 60_001 }.max_samples_per_dispatch(),
            None
        );
    }
}
