//! `rt-gpu merge`: film files of disjoint sample ranges of one render combined into one.

use super::args::MergeArgs;
use super::shown_radiance;
use rt_gpu::film::file as film_file;
use rt_gpu::film::output::{ImageFormat, PendingOutput};
use std::io::Write;
use std::path::Path;

/// Combines film files of disjoint sample ranges of one render.
pub fn merge(args: &MergeArgs) -> anyhow::Result<()> {
    ImageFormat::from_path(&args.output)?;
    let inputs: Vec<&Path> = args.films.iter().map(|p| p.as_path()).collect();
    let pending = PendingOutput::claim(&args.output, &inputs)?;
    let mut films = Vec::new();
    for path in &args.films {
        let (film, meta) = film_file::read(path)?;
        films.push(film_file::NamedFilm {
            name: path.display().to_string(),
            film,
            meta,
        });
    }
    let combined = film_file::combine(films)?;
    let (merged, meta) = (combined.film, combined.meta);
    if !combined.missing.is_empty() {
        note!(
            "warning: samples {} are missing: the image holds the others' {} spp (merge the missing films too for the full render)",
            film_file::format_ranges(&combined.missing),
            meta.spp()
        );
    }
    pending.commit_render(&merged, &meta, args.gamma)?;
    let mean = merged.image_mean();
    note!(
        "merged {} films: samples {}, {}x{}, mean radiance {}, estimated RMSE {:.3e} -> {}",
        args.films.len(),
        film_file::format_ranges(&meta.samples),
        merged.width,
        merged.height,
        shown_radiance(mean),
        merged.estimated_rmse(),
        args.output.display()
    );
    Ok(())
}
