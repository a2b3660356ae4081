//! `rt-gpu view`: a window showing the film as it accumulates, on the device that renders it.
//! Each frame adds samples for about a frame's time (`film.rs`), then the display pass
//! (`gpu::display`) draws the accumulator into the window's image: the film never comes back
//! to the host to be shown. Camera moves (`controls.rs`) restart the film, so what is shown is
//! always an unbiased render of the current view. The same backends, kernel, sampler and film
//! as batch renders: a film saved here is the one `rt-gpu SCENE` writes for that camera.

pub mod controls;
pub mod denoised;
pub mod film;

use crate::film::file::FilmMeta;
use crate::film::output::{PendingOutput, Transfer};
use crate::gpu::display::{DisplayPass, read_texture, shows_levels_exactly};
use crate::gpu::{Features, GpuContext};
use crate::options::{Backend, RenderOptions};
use crate::render::GpuChoice;
use crate::scene::Scene;
use crate::scene::flat::FlatScene;
use crate::shared::layout::ACCUM_BYTES_PER_PIXEL;
use anyhow::{Context, anyhow, bail};
use controls::{Input, camera_table, moved};
use denoised::Denoised;
use film::LiveFilm;
use std::collections::VecDeque;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key, ModifiersState, NamedKey};
use winit::window::{Window, WindowId};

/// A step of a scripted session (tests): an input, or a wait.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Step {
    Input(Input),
    /// Wait until the film holds this many samples per pixel.
    Spp(u32),
}

impl Step {
    /// `orbit:DX,DY`, `pan:DX,DY`, `dolly:STEPS`, `fly:F,R,U`, `save`, `camera`, `restart`,
    /// `reload`, `denoise`, `quit` or `spp:N`.
    pub fn parse(text: &str) -> Result<Self, String> {
        let (verb, rest) = text.split_once(':').unwrap_or((text, ""));
        let numbers = || -> Result<Vec<f32>, String> {
            rest.split(',')
                .map(|n| {
                    n.trim()
                        .parse::<f32>()
                        .map_err(|_| format!("'{n}' is not a number"))
                })
                .collect()
        };
        let pair = || match numbers()?.as_slice() {
            &[a, b] => Ok((a, b)),
            _ => Err(format!("{verb} takes two numbers, as {verb}:10,0")),
        };
        Ok(Step::Input(match verb {
            "orbit" => pair().map(|(a, b)| Input::Orbit(a, b))?,
            "pan" => pair().map(|(a, b)| Input::Pan(a, b))?,
            "dolly" => match numbers()?.as_slice() {
                &[s] => Input::Dolly(s),
                _ => return Err("dolly takes one number, as dolly:2".into()),
            },
            "fly" => match numbers()?.as_slice() {
                &[f, r, u] => Input::Fly(glam::Vec3::new(f, r, u)),
                _ => return Err("fly takes three numbers, as fly:1,0,0".into()),
            },
            "save" => Input::Save,
            "camera" => Input::PrintCamera,
            "restart" => Input::Restart,
            "reload" => Input::Reload,
            "denoise" => Input::Denoise,
            "quit" => Input::Quit,
            "spp" => {
                return rest
                    .trim()
                    .parse()
                    .map(Step::Spp)
                    .map_err(|_| format!("spp takes a sample count, as spp:4, not '{rest}'"));
            }
            _ => {
                return Err(format!(
                    "unknown step '{verb}': expected orbit, pan, dolly, fly, save, camera, restart, reload, denoise, quit or spp"
                ));
            }
        }))
    }
}

/// What `rt-gpu view` was asked for.
pub struct ViewConfig {
    pub scene: Scene,
    /// The window's first size is `opts.width` x `opts.height`; `opts.spp` is ignored.
    pub opts: RenderOptions,
    pub backend: Backend,
    pub gpu: GpuChoice,
    /// Stop adding samples at this many per pixel, or after this many seconds of a view (the
    /// image stays shown).
    pub stop_spp: Option<u32>,
    pub stop_seconds: Option<f64>,
    /// Where Ctrl+S writes the film file (.exr), with a PNG beside it.
    pub output: PathBuf,
    /// Test aids: scripted steps, run in order as frames pass; exit once the film holds this
    /// many samples (after the script), writing the window's image to `screenshot`.
    pub script: Vec<Step>,
    pub exit_after_spp: Option<u32>,
    pub screenshot: Option<PathBuf>,
    /// Reads the scene again (F5): its file and what it reads, as they are now.
    pub reload: Option<Box<dyn Fn() -> anyhow::Result<Scene>>>,
}

/// Opens the window and runs until it is closed (or the test aids end it).
pub fn run(config: ViewConfig) -> anyhow::Result<()> {
    if std::env::var_os("DISPLAY").is_none_or(|d| d.is_empty()) {
        bail!("no display: set DISPLAY, or render to a file with rt-gpu SCENE");
    }
    let event_loop = EventLoop::new().map_err(|e| {
        // winit's message starts with where in its source it failed: only the reason is kept.
        let message = e.to_string();
        let reason = message.rsplit(": ").next().unwrap_or(&message);
        anyhow!(
            "cannot open the display {} ({reason}): set DISPLAY to a running X server, or render to a file with rt-gpu SCENE",
            std::env::var("DISPLAY").unwrap_or_default()
        )
    })?;
    let mut app = App {
        config,
        viewer: None,
        error: None,
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| anyhow!("the window's event loop failed: {e}"))?;
    if let Some(e) = app.error {
        return Err(e);
    }
    if let Some(v) = &app.viewer {
        let seconds = v.opened.elapsed().as_secs_f64();
        let _ = writeln!(
            std::io::stderr().lock(),
            "viewed {}: {} frames in {seconds:.1} s ({:.1} frames/s; {:.1} s rendering, {:.1} s displaying), {:.2} Msamples/s, {} spp at the end",
            v.scene.name,
            v.frames,
            v.frames as f64 / seconds,
            v.render_seconds,
            v.display_seconds,
            v.samples as f64 / seconds * 1e-6,
            v.film.spp()
        );
    }
    Ok(())
}

/// A flat scene and its film, made for the window before they replace the shown ones.
struct Built {
    flat: FlatScene,
    features: Option<Features>,
    film: LiveFilm,
    opts: RenderOptions,
    scale: u32,
}

struct App {
    config: ViewConfig,
    viewer: Option<Viewer>,
    error: Option<anyhow::Error>,
}

impl App {
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        self.error.get_or_insert(e);
        event_loop.exit();
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.viewer.is_some() {
            return;
        }
        match Viewer::open(event_loop, &self.config) {
            Ok(v) => self.viewer = Some(v),
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(viewer) = self.viewer.as_mut() else {
            return;
        };
        let result = match event {
            // Closed by the window manager, or destroyed by another client: a normal end.
            WindowEvent::CloseRequested | WindowEvent::Destroyed => {
                event_loop.exit();
                Ok(())
            }
            WindowEvent::RedrawRequested => viewer.frame(&self.config, event_loop),
            event => viewer.handle(&self.config, event_loop, event),
        };
        if let Err(e) = result {
            self.fail(event_loop, e);
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(viewer) = &self.viewer {
            if viewer.busy(&self.config) {
                event_loop.set_control_flow(ControlFlow::Poll);
                viewer.window.request_redraw();
            } else {
                event_loop.set_control_flow(ControlFlow::Wait);
            }
        }
    }
}

/// The window, its device and the film it shows.
struct Viewer {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    surface_config: wgpu::SurfaceConfiguration,
    /// The format the display pass draws in (the surface's, without the sRGB curve).
    view_format: wgpu::TextureFormat,
    ctx: GpuContext,
    display: DisplayPass,
    display_group: wgpu::BindGroup,
    /// The scene with the current camera, flattened for the current film size.
    scene: Scene,
    /// The camera the scene's file gave when last read: a reload keeps the window's view
    /// unless the file's camera changed.
    file_camera: crate::scene::Camera,
    flat: FlatScene,
    opts: RenderOptions,
    /// Window pixels per film pixel (a window too large for one storage binding shows an
    /// enlarged film).
    scale: u32,
    gpu_features: Option<Features>,
    film: LiveFilm,
    /// Open Image Denoise, opened at the first N; the denoised display.
    denoiser: Option<Arc<crate::denoise::Denoiser>>,
    denoised: Denoised,
    /// When this view's film started, and samples since then.
    view_start: Instant,
    status_at: Instant,
    error_estimate: Option<(f64, Instant)>,
    buttons: (bool, bool),
    modifiers: ModifiersState,
    cursor: Option<(f64, f64)>,
    script: VecDeque<Step>,
    /// Frames in a row whose window image could not be configured.
    lost_frames: u32,
    /// For the summary: when the window opened, frames drawn, samples rendered since.
    opened: Instant,
    frames: u64,
    samples: u64,
    render_seconds: f64,
    display_seconds: f64,
}

impl Viewer {
    fn open(event_loop: &ActiveEventLoop, config: &ViewConfig) -> anyhow::Result<Self> {
        let opts = config.opts;
        let window = Arc::new(
            event_loop
                .create_window(
                    Window::default_attributes()
                        .with_title(format!("rt-gpu view {}", config.scene.name))
                        .with_inner_size(PhysicalSize::new(opts.width, opts.height)),
                )
                .map_err(|e| anyhow!("cannot open a window: {e}"))?,
        );
        let instance = crate::gpu::context::instance();
        let surface = instance
            .create_surface(window.clone())
            .map_err(|e| anyhow!("cannot draw into the window: {e}"))?;
        let adapter =
            crate::gpu::context::choose_adapter(&instance, config.gpu.adapter.as_deref())?;
        if !adapter.is_surface_supported(&surface) {
            bail!(
                "the GPU adapter {} cannot show a window on this display: pick another with --adapter (see `rt-gpu devices`)",
                adapter.get_info().name
            );
        }
        let ctx = GpuContext::open(&adapter)?;
        // A surface larger than the device's textures fails in wgpu's validation, not here.
        let limit = ctx.device.limits().max_texture_dimension_2d;
        let size = window.inner_size();
        for (what, (w, h)) in [
            ("the image", (opts.width, opts.height)),
            ("the window", (size.width, size.height)),
        ] {
            if w > limit || h > limit {
                bail!(
                    "{what} is {w}x{h}, larger than the {limit} pixels a side this GPU's surfaces take: use a smaller --size"
                );
            }
        }
        let caps = surface.get_capabilities(&adapter);
        let exact = caps
            .formats
            .iter()
            .copied()
            .find(|f| shows_levels_exactly(f.remove_srgb_suffix()));
        let format = exact
            .or_else(|| caps.formats.first().copied())
            .context("the window offers no image format to draw in")?;
        let view_format = format.remove_srgb_suffix();
        if exact.is_none() {
            warn(&format!(
                "the window's image format {format:?} re-encodes what is drawn: colours are close to, not exactly, the image file's"
            ));
        }
        let size = window.inner_size();
        let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
        if caps.usages.contains(wgpu::TextureUsages::COPY_SRC) {
            usage |= wgpu::TextureUsages::COPY_SRC;
        }
        let surface_config = wgpu::SurfaceConfiguration {
            usage,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::Fifo,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps
                .alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto),
            color_space: wgpu::SurfaceColorSpace::Auto,
            view_formats: if view_format != format {
                vec![view_format]
            } else {
                vec![]
            },
        };
        surface.configure(&ctx.device, &surface_config);
        let display = DisplayPass::new(&ctx, view_format, &Transfer::Srgb.levels())?;
        let scene = config.scene.clone();
        let (opts, scale) = film_size(&ctx, &opts, size.width, size.height);
        let flat = FlatScene::new(&scene, opts.width, opts.height).context("invalid scene")?;
        let gpu_features = match config.backend {
            Backend::Gpu => Some(config.gpu.features(&flat, opts.integrator)),
            Backend::Cpu => None,
        };
        let film = LiveFilm::new(&ctx, gpu_features, &flat, &opts)?;
        display.set_film(&ctx, opts.width, opts.height, scale);
        let display_group = display.bind(&ctx, film.accumulator());
        let now = Instant::now();
        Ok(Viewer {
            window,
            surface,
            surface_config,
            view_format,
            ctx,
            display,
            display_group,
            file_camera: scene.camera.clone(),
            scene,
            flat,
            opts,
            scale,
            gpu_features,
            film,
            denoiser: None,
            denoised: Denoised::Off,
            view_start: now,
            status_at: now,
            error_estimate: None,
            buttons: (false, false),
            modifiers: ModifiersState::empty(),
            cursor: None,
            script: config.script.iter().copied().collect(),
            lost_frames: 0,
            opened: now,
            frames: 0,
            samples: 0,
            render_seconds: 0.0,
            display_seconds: 0.0,
        })
    }

    /// Samples per pixel this view stops at.
    fn target_spp(&self, config: &ViewConfig) -> u32 {
        let script_waits = self.script.iter().any(|s| matches!(s, Step::Spp(_)));
        match (config.exit_after_spp, config.stop_spp) {
            _ if script_waits => u32::MAX,
            (Some(n), _) | (None, Some(n)) => n,
            (None, None) => u32::MAX,
        }
    }

    /// Whether frames should keep coming: samples to add, or a script to run.
    fn busy(&self, config: &ViewConfig) -> bool {
        let time_left = config
            .stop_seconds
            .is_none_or(|t| self.view_start.elapsed().as_secs_f64() < t);
        !self.script.is_empty()
            || (self.film.spp() < self.target_spp(config) && time_left)
            || matches!(self.denoised, Denoised::Pending { .. })
    }

    /// One frame: the script's next steps, samples for about a frame's time, the display pass.
    fn frame(&mut self, config: &ViewConfig, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        while let Some(&step) = self.script.front() {
            match step {
                Step::Spp(n) if self.film.spp() < n => break,
                Step::Spp(_) => {}
                Step::Input(input) => self.apply(config, event_loop, input)?,
            }
            self.script.pop_front();
        }
        let time_left = config
            .stop_seconds
            .is_none_or(|t| self.view_start.elapsed().as_secs_f64() < t);
        let most = match self.script.front() {
            Some(Step::Spp(n)) => *n,
            _ => self.target_spp(config),
        };
        if time_left && self.film.spp() < most {
            let start = Instant::now();
            let added = self.film.advance(&self.flat, FRAME_SECONDS, most)?;
            self.render_seconds += start.elapsed().as_secs_f64();
            self.samples += added as u64 * self.opts.width as u64 * self.opts.height as u64;
        }
        let polled =
            (self.denoised).poll(&self.ctx, &self.display, self.opts.width, self.opts.height);
        if let Err(e) = polled {
            // The live film stays shown: the window goes on.
            warn(&format!("not denoised: {e:#}"));
        }
        // A denoise under way is waited for: a test's screenshot shows what it asked for.
        let finished = self.script.is_empty()
            && config.exit_after_spp.is_some_and(|n| self.film.spp() >= n)
            && !matches!(self.denoised, Denoised::Pending { .. });
        if finished || !self.busy(config) {
            // What is shown then is exactly the film of spp() samples.
            self.film.complete()?;
        }
        let shot = if finished {
            config.screenshot.as_deref()
        } else {
            None
        };
        let start = Instant::now();
        self.draw(shot)?;
        self.ctx.wait()?;
        self.display_seconds += start.elapsed().as_secs_f64();
        self.frames += 1;
        self.update_status(false)?;
        if finished {
            event_loop.exit();
        }
        Ok(())
    }

    /// Draws the film into the window (and into `screenshot`, a PNG, if given).
    fn draw(&mut self, screenshot: Option<&Path>) -> anyhow::Result<()> {
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                // A window being destroyed (its Destroyed event still to come) refuses a new
                // configuration: a few frames are skipped, then it is an error.
                let scope = self
                    .ctx
                    .device
                    .push_error_scope(wgpu::ErrorFilter::Validation);
                self.surface
                    .configure(&self.ctx.device, &self.surface_config);
                if let Some(e) = pollster::block_on(scope.pop()) {
                    self.lost_frames += 1;
                    if self.lost_frames > MAX_LOST_FRAMES {
                        bail!(
                            "the window's image was lost: {}",
                            e.to_string().replace('\n', " ")
                        );
                    }
                } else {
                    self.lost_frames = 0;
                }
                return Ok(());
            }
            // Hidden or busy: the next frame draws.
            _ => return Ok(()),
        };
        let view = frame.texture.create_view(&wgpu::TextureViewDescriptor {
            format: Some(self.view_format),
            ..Default::default()
        });
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        self.display.draw(&mut encoder, &view, self.shown_group());
        self.ctx.queue.submit([encoder.finish()]);
        if let Some(path) = screenshot {
            let texture = if self
                .surface_config
                .usage
                .contains(wgpu::TextureUsages::COPY_SRC)
            {
                frame.texture.clone()
            } else {
                self.offscreen_copy()?
            };
            let rgb = read_texture(&self.ctx, &texture)?;
            let inputs: Vec<&Path> = self.scene.input_paths().collect();
            write_png(path, &inputs, texture.width(), texture.height(), rgb)?;
        }
        self.ctx.queue.present(frame);
        if let Some(e) = self.ctx.take_failure() {
            return Err(e.into());
        }
        Ok(())
    }

    /// The display pass drawn into a texture of the window's size (for a screenshot where the
    /// window's own image cannot be copied).
    fn offscreen_copy(&self) -> anyhow::Result<wgpu::Texture> {
        let texture = self.ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("screenshot"),
            size: wgpu::Extent3d {
                width: self.surface_config.width,
                height: self.surface_config.height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: self.view_format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        self.display.draw(&mut encoder, &view, self.shown_group());
        self.ctx.queue.submit([encoder.finish()]);
        Ok(texture)
    }

    /// The display pass's bindings to what is shown: the denoised film, else the live one.
    fn shown_group(&self) -> &wgpu::BindGroup {
        match &self.denoised {
            Denoised::Shown { group, .. } => group,
            _ => &self.display_group,
        }
    }

    /// N: the film as it stands denoised (shown when ready), or the live film again. Without
    /// OIDN, a warning saying how to install it; the window goes on.
    fn toggle_denoised(&mut self) -> anyhow::Result<()> {
        if !matches!(self.denoised, Denoised::Off) {
            self.denoised = Denoised::Off;
            return self.update_status(true);
        }
        if self.film.spp() == 0 {
            return Ok(()); // nothing to denoise yet
        }
        let denoiser = match &self.denoiser {
            Some(d) => d.clone(),
            None => match crate::denoise::Denoiser::new(None) {
                Ok(d) => self.denoiser.insert(Arc::new(d)).clone(),
                Err(e) => {
                    warn(&format!("not denoised: {e}"));
                    return Ok(());
                }
            },
        };
        self.film.complete()?;
        let film = self.film.film()?;
        self.denoised = Denoised::start(denoiser, self.scene.clone(), self.opts, film);
        self.window.request_redraw();
        self.update_status(true)
    }

    /// The window title: spp, speed, the estimated error, and what renders.
    fn update_status(&mut self, now: bool) -> anyhow::Result<()> {
        if !now && self.status_at.elapsed().as_secs_f64() < STATUS_SECONDS {
            return Ok(());
        }
        self.status_at = Instant::now();
        let spp = self.film.spp();
        let seconds = self.view_start.elapsed().as_secs_f64();
        let rate =
            spp as f64 * self.opts.width as f64 * self.opts.height as f64 / seconds.max(1e-9);
        // The error needs the film on the host: estimated now and then, not every frame.
        let stale = self
            .error_estimate
            .is_none_or(|(_, at)| at.elapsed().as_secs_f64() > ERROR_SECONDS);
        if stale && spp >= 4 {
            let film = self.film.film()?;
            self.error_estimate = Some((film.estimated_rmse(), Instant::now()));
        }
        let error = match self.error_estimate {
            Some((e, _)) if spp >= 4 => format!(", RMSE ~{e:.2e}"),
            _ => String::new(),
        };
        let backend = if self.gpu_features.is_some() {
            "gpu"
        } else {
            "cpu"
        };
        self.window.set_title(&format!(
            "rt-gpu view {}: {spp} spp, {:.2} Msamples/s{error}, {backend}: {}{}",
            self.scene.name,
            rate * 1e-6,
            self.film.device(),
            self.denoised.status()
        ));
        Ok(())
    }

    /// A window event: mouse and keys become [`Input`]s.
    fn handle(
        &mut self,
        config: &ViewConfig,
        event_loop: &ActiveEventLoop,
        event: WindowEvent,
    ) -> anyhow::Result<()> {
        let input = match event {
            WindowEvent::Resized(size) => return self.resize(size.width, size.height),
            WindowEvent::ModifiersChanged(m) => {
                self.modifiers = m.state();
                None
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let down = state == ElementState::Pressed;
                match button {
                    MouseButton::Left => self.buttons.0 = down,
                    MouseButton::Right => self.buttons.1 = down,
                    _ => {}
                }
                None
            }
            WindowEvent::CursorMoved { position, .. } => {
                let last = self.cursor.replace((position.x, position.y));
                match last {
                    Some((x, y)) if self.buttons.0 || self.buttons.1 => {
                        let (dx, dy) = ((position.x - x) as f32, (position.y - y) as f32);
                        if self.buttons.1 || self.modifiers.shift_key() {
                            Some(Input::Pan(dx, dy))
                        } else {
                            Some(Input::Orbit(dx, dy))
                        }
                    }
                    _ => None,
                }
            }
            WindowEvent::MouseWheel { delta, .. } => Some(Input::Dolly(match delta {
                MouseScrollDelta::LineDelta(_, y) => y,
                MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
            })),
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                key_input(&event.logical_key, self.modifiers)
            }
            _ => None,
        };
        match input {
            Some(input) => self.apply(config, event_loop, input),
            None => Ok(()),
        }
    }

    /// Does what `input` asks: a camera move restarts the film.
    fn apply(
        &mut self,
        config: &ViewConfig,
        event_loop: &ActiveEventLoop,
        input: Input,
    ) -> anyhow::Result<()> {
        match input {
            Input::Save => self.save(config),
            Input::PrintCamera => {
                let mut out = std::io::stdout().lock();
                let _ = writeln!(out, "{}", camera_table(&self.scene.camera));
                let _ = out.flush();
                Ok(())
            }
            Input::Restart => self.restart(),
            Input::Reload => self.reload(config),
            Input::Denoise => self.toggle_denoised(),
            Input::Quit => {
                event_loop.exit();
                Ok(())
            }
            _ => {
                let Some(camera) = moved(&self.scene.camera, input, self.surface_config.height)
                else {
                    return Ok(());
                };
                self.scene.camera = camera;
                if !self
                    .flat
                    .set_camera(&self.scene, self.opts.width, self.opts.height)
                {
                    // The camera left the scene's recentring cell: flattened and compiled again.
                    return self.rebuild();
                }
                self.restart()
            }
        }
    }

    fn restart(&mut self) -> anyhow::Result<()> {
        self.denoised = Denoised::Off;
        self.film.restart(&self.flat)?;
        self.view_start = Instant::now();
        self.error_estimate = None;
        self.window.request_redraw();
        Ok(())
    }

    /// The scene read again (its file edited, say): what the old one read and the new one does
    /// not (images, meshes) is freed with it. A scene that no longer reads is a warning, and the
    /// window goes on showing the one it has.
    fn reload(&mut self, config: &ViewConfig) -> anyhow::Result<()> {
        let Some(reload) = &config.reload else {
            return Ok(());
        };
        let mut scene = match reload() {
            Ok(scene) => scene,
            Err(e) => {
                warn(&format!("not reloaded: {e:#}"));
                return Ok(());
            }
        };
        let file_camera = scene.camera.clone();
        if file_camera == self.file_camera {
            scene.camera = self.scene.camera.clone();
        }
        // Built before anything is replaced: a scene that reads but cannot be shown (a texture
        // larger than the device holds, say) leaves the window showing the one it has. The
        // kernel is made for the new scene's features.
        let on_gpu = self.gpu_features.is_some();
        let built = self.build(&scene, |flat, integrator| {
            on_gpu.then(|| config.gpu.features(flat, integrator))
        });
        let built = match built {
            Ok(built) => built,
            Err(e) => {
                warn(&format!("not reloaded: {e:#}"));
                return Ok(());
            }
        };
        (self.scene, self.file_camera) = (scene, file_camera);
        self.show(built)?;
        let _ = writeln!(
            std::io::stderr().lock(),
            "reloaded {}: {} image files and {} mesh files held",
            self.scene.name,
            crate::assets::image::files_held(),
            crate::scene::mesh::files_held()
        );
        Ok(())
    }

    /// A new film for the current window size and scene (flattened again).
    fn rebuild(&mut self) -> anyhow::Result<()> {
        let features = self.gpu_features;
        let built = self.build(&self.scene, |_, _| features)?;
        self.show(built)
    }

    /// `scene` flattened and a film of it for the current window size, on the kernel with the
    /// features `features` gives for the flat scene (`None`: the CPU backend).
    fn build(
        &self,
        scene: &Scene,
        features: impl FnOnce(&FlatScene, crate::options::Integrator) -> Option<Features>,
    ) -> anyhow::Result<Built> {
        let size = self.window.inner_size();
        let (opts, scale) = film_size(&self.ctx, &self.opts, size.width, size.height);
        let flat = FlatScene::new(scene, opts.width, opts.height).context("invalid scene")?;
        let features = features(&flat, opts.integrator);
        let film = LiveFilm::new(&self.ctx, features, &flat, &opts)?;
        Ok(Built {
            flat,
            features,
            film,
            opts,
            scale,
        })
    }

    /// Shows what [`Self::build`] made, from its first sample.
    fn show(&mut self, built: Built) -> anyhow::Result<()> {
        let Built {
            flat,
            features,
            film,
            opts,
            scale,
        } = built;
        (self.flat, self.gpu_features, self.film) = (flat, features, film);
        (self.opts, self.scale) = (opts, scale);
        self.display
            .set_film(&self.ctx, opts.width, opts.height, scale);
        self.display_group = self.display.bind(&self.ctx, self.film.accumulator());
        self.restart()
    }

    fn resize(&mut self, width: u32, height: u32) -> anyhow::Result<()> {
        if width == 0 || height == 0 {
            return Ok(());
        }
        if (width, height) == (self.surface_config.width, self.surface_config.height) {
            return Ok(());
        }
        self.surface_config.width = width;
        self.surface_config.height = height;
        self.surface
            .configure(&self.ctx.device, &self.surface_config);
        self.rebuild()
    }

    /// Writes the film (the film file and a PNG beside it), as `rt-gpu` writes a render of
    /// this camera, spp and options.
    fn save(&mut self, config: &ViewConfig) -> anyhow::Result<()> {
        let film = self.film.film()?;
        let spp = self.film.spp();
        let opts = RenderOptions {
            spp,
            first_sample: 0,
            ..self.opts
        };
        let meta = FilmMeta {
            identity: crate::render::request::identity(
                &self.scene,
                config.backend,
                &opts,
                config.gpu.everything,
            ),
            samples: std::iter::once(0..spp).collect(),
            device: self.film.device(),
        };
        let png = config.output.with_extension("png");
        let inputs: Vec<&Path> = self.scene.input_paths().collect();
        PendingOutput::claim(&config.output, &inputs)?.commit_film(&film, &meta)?;
        PendingOutput::claim(&png, &inputs)?.commit_image(&film, None)?;
        let _ = writeln!(
            std::io::stderr().lock(),
            "wrote {} and {} ({spp} spp)",
            config.output.display(),
            png.display()
        );
        Ok(())
    }
}

/// Seconds of samples per frame: 30 frames a second where the device keeps up.
const FRAME_SECONDS: f64 = 1.0 / 30.0;
/// How often the title is updated, and the error estimated (it reads the film back).
const STATUS_SECONDS: f64 = 0.25;
const ERROR_SECONDS: f64 = 2.0;
/// Frames in a row without a window image before that is an error.
const MAX_LOST_FRAMES: u32 = 100;

/// The film for a `width` x `height` window: the window's size, or a fraction of it each way
/// where that does not fit one storage binding; and the window pixels per film pixel.
fn film_size(
    ctx: &GpuContext,
    opts: &RenderOptions,
    width: u32,
    height: u32,
) -> (RenderOptions, u32) {
    let binding = ctx
        .limits
        .max_storage_buffer_binding_size
        .min(ctx.limits.max_buffer_size);
    let most = binding / ACCUM_BYTES_PER_PIXEL;
    let (width, height) = (width.max(1), height.max(1));
    let mut scale = 1;
    while (width.div_ceil(scale) as u64) * (height.div_ceil(scale) as u64) > most {
        scale += 1;
    }
    let opts = RenderOptions {
        width: width.div_ceil(scale),
        height: height.div_ceil(scale),
        ..*opts
    };
    (opts, scale)
}

/// A key press as an input: WASD/QE fly, Ctrl+S saves (S alone is the backward step), C
/// prints the camera, R restarts, N toggles the denoised display, Esc quits.
fn key_input(key: &Key, modifiers: ModifiersState) -> Option<Input> {
    use glam::Vec3;
    match key {
        Key::Named(NamedKey::Escape) => Some(Input::Quit),
        Key::Character(c) => match c.to_lowercase().as_str() {
            "s" if modifiers.control_key() => Some(Input::Save),
            "w" => Some(Input::Fly(Vec3::X)),
            "s" => Some(Input::Fly(-Vec3::X)),
            "d" => Some(Input::Fly(Vec3::Y)),
            "a" => Some(Input::Fly(-Vec3::Y)),
            "e" => Some(Input::Fly(Vec3::Z)),
            "q" => Some(Input::Fly(-Vec3::Z)),
            "c" => Some(Input::PrintCamera),
            "r" => Some(Input::Restart),
            "n" => Some(Input::Denoise),
            _ => None,
        },
        Key::Named(NamedKey::F5) => Some(Input::Reload),
        _ => None,
    }
}

/// Writes a screenshot, never onto one of `inputs` (the files the scene reads).
fn write_png(
    path: &Path,
    inputs: &[&Path],
    width: u32,
    height: u32,
    rgb: Vec<u8>,
) -> anyhow::Result<()> {
    let image = image::RgbImage::from_raw(width, height, rgb).context("screenshot size")?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write_to(&mut bytes, image::ImageFormat::Png)?;
    PendingOutput::claim(path, inputs)?.commit(&bytes.into_inner())
}

fn warn(message: &str) {
    let _ = writeln!(std::io::stderr().lock(), "warning: {message}");
}
