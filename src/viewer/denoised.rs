//! The viewer's denoised display (key N): the film as it stands, denoised off the render loop
//! (on a thread: the feature buffers rendered by the CPU backend from the film's first samples,
//! then Open Image Denoise), shown when ready in place of the live film, through the same
//! display pass (the denoised image uploaded as a film of one sample a pixel): on the CPU
//! backend exactly the image `--denoise` writes; on the kernel, its film with the CPU's buffers
//! (the window's device is the render loop's). The render goes on underneath; N again, or
//! anything that restarts the film, shows the live film (a denoise under way stops after its
//! current step).

use crate::denoise::{Denoiser, render_feature_buffers};
use crate::film::Film;
use crate::film::float_image::film_of;
use crate::gpu::GpuContext;
use crate::gpu::display::{DisplayPass, accumulator_words};
use crate::options::RenderOptions;
use crate::scene::Scene;
use crate::scene::flat::FlatScene;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, TryRecvError, channel};
use wgpu::util::DeviceExt;

/// What the window shows of denoising.
pub enum Denoised {
    Off,
    /// Being denoised (of a film of `spp` samples). Dropping it (N again, a restart) tells the
    /// thread, which stops after the step under way.
    Pending {
        spp: u32,
        result: Receiver<anyhow::Result<Vec<[f32; 3]>>>,
        _wanted: Arc<()>,
    },
    /// Shown: the display pass's bindings to the denoised image.
    Shown {
        spp: u32,
        group: wgpu::BindGroup,
        // Held while the group binds it.
        _buffer: wgpu::Buffer,
    },
}

impl Denoised {
    /// Starts denoising `film` (of `scene` rendered with `opts`, `film.spp` samples) on a
    /// thread.
    pub fn start(
        denoiser: Arc<Denoiser>,
        scene: Scene,
        opts: RenderOptions,
        film: Film,
    ) -> Denoised {
        let spp = film.pixels.first().map_or(0, |p| p.n as u32);
        let (send, result) = channel();
        let wanted = Arc::new(());
        let still_wanted = Arc::downgrade(&wanted);
        std::thread::spawn(move || {
            let denoised = (|| {
                let abandoned = || anyhow::anyhow!("abandoned");
                let flat = FlatScene::new(&scene, opts.width, opts.height)?;
                // The film's samples start at 0.
                let image_opts = RenderOptions {
                    first_sample: 0,
                    ..opts
                };
                let (features, _) = render_feature_buffers(&image_opts, spp, |opts| {
                    if still_wanted.strong_count() == 0 {
                        return Err(abandoned());
                    }
                    Ok(crate::cpu::render(&flat, opts, &|| {}))
                })?;
                if still_wanted.strong_count() == 0 {
                    return Err(abandoned());
                }
                Ok(denoiser.denoise(film.width, film.height, &film.mean_rgb(), Some(&features))?)
            })();
            // The window may have moved on: nobody listening is fine.
            let _ = send.send(denoised);
        });
        Denoised::Pending {
            spp,
            result,
            _wanted: wanted,
        }
    }

    /// A finished denoise made ready to show through `display`; an error ends it (the live film
    /// is shown again).
    pub fn poll(
        &mut self,
        ctx: &GpuContext,
        display: &DisplayPass,
        width: u32,
        height: u32,
    ) -> anyhow::Result<()> {
        let Denoised::Pending { spp, result, .. } = self else {
            return Ok(());
        };
        let image = match result.try_recv() {
            Ok(image) => image,
            Err(TryRecvError::Empty) => return Ok(()),
            Err(TryRecvError::Disconnected) => Err(anyhow::anyhow!("the denoising thread ended")),
        };
        let spp = *spp;
        *self = Denoised::Off;
        // As the batch render writes it: the window shows a denoised PNG's bytes.
        let film = film_of(width, height, &image?);
        let buffer = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("denoised film"),
                contents: bytemuck::cast_slice(&accumulator_words(&film)),
                usage: wgpu::BufferUsages::STORAGE,
            });
        let group = display.bind(ctx, &buffer);
        *self = Denoised::Shown {
            spp,
            group,
            _buffer: buffer,
        };
        Ok(())
    }

    /// The title's words on it.
    pub fn status(&self) -> String {
        match self {
            Denoised::Off => String::new(),
            Denoised::Pending { spp, .. } => format!(", denoising {spp} spp..."),
            Denoised::Shown { spp, .. } => format!(", denoised at {spp} spp (N: live)"),
        }
    }
}
