//! The viewer's display pass (shaders/display.wgsl): a film's accumulator on the device drawn
//! into a window's image as the 8-bit levels an image file of the same film holds, without
//! reading the film back. A CPU film is uploaded in the accumulator's layout and drawn the same
//! way.

use super::context::{GpuContext, GpuError};
use super::shader::validate;
use crate::film::Film;
use crate::film::levels::Levels;
use crate::shared::exact_sum::SUM_WORDS;
use crate::shared::layout::{
    ACCUM_COUNT, ACCUM_EVEN_SUM, ACCUM_ODD_SUM, ACCUM_WORDS, GpuDisplay, WgslStruct,
};
use wgpu::util::DeviceExt;

/// The display shader: the generated `Display` struct and layout constants, then the pass.
pub fn display_source() -> String {
    format!(
        "{}\nconst ACCUM_WORDS: u32 = {ACCUM_WORDS}u;\nconst ACCUM_COUNT: u32 = {ACCUM_COUNT}u;\nconst ACCUM_EVEN_SUM: u32 = {ACCUM_EVEN_SUM}u;\nconst ACCUM_ODD_SUM: u32 = {ACCUM_ODD_SUM}u;\nconst SUM_WORDS: u32 = {SUM_WORDS}u;\n\n{}",
        GpuDisplay::wgsl_declaration(),
        include_str!("../../shaders/display.wgsl")
    )
}

/// Whether `format` stores what the display pass writes unchanged: 8-bit unorm without the
/// sRGB curve (which would encode the levels again).
pub fn shows_levels_exactly(format: wgpu::TextureFormat) -> bool {
    matches!(
        format,
        wgpu::TextureFormat::Rgba8Unorm | wgpu::TextureFormat::Bgra8Unorm
    )
}

pub struct DisplayPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    thresholds: wgpu::Buffer,
    /// The format of the images it draws into.
    pub format: wgpu::TextureFormat,
}

impl DisplayPass {
    /// A pass drawing into images of `format` with `levels` (the image files' transfer curve).
    pub fn new(
        ctx: &GpuContext,
        format: wgpu::TextureFormat,
        levels: &Levels,
    ) -> Result<Self, GpuError> {
        let source = display_source();
        validate(&source).map_err(GpuError::Shader)?;
        let device = &ctx.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("display"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("display"),
            entries: &[
                entry(0, wgpu::BufferBindingType::Uniform),
                entry(1, wgpu::BufferBindingType::Storage { read_only: true }),
                entry(2, wgpu::BufferBindingType::Uniform),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("display"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("display"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vertex"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fragment"),
                compilation_options: Default::default(),
                targets: &[Some(format.into())],
            }),
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        });
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("display"),
            size: std::mem::size_of::<GpuDisplay>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bits: Vec<u32> = levels.thresholds.iter().map(|t| t.to_bits()).collect();
        let thresholds = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("display thresholds"),
            contents: bytemuck::cast_slice(&bits),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        if let Some(e) = ctx.take_failure() {
            return Err(e);
        }
        Ok(DisplayPass {
            pipeline,
            layout,
            params,
            thresholds,
            format,
        })
    }

    /// The film's size and how many image pixels one film pixel covers each way.
    pub fn set_film(&self, ctx: &GpuContext, width: u32, height: u32, scale: u32) {
        let params = GpuDisplay {
            film_size: [width, height],
            scale: scale.max(1),
            _pad: 0,
        };
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
    }

    /// What a draw binds: `accumulator`, in the kernel's layout.
    pub fn bind(&self, ctx: &GpuContext, accumulator: &wgpu::Buffer) -> wgpu::BindGroup {
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("display"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: self.params.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: accumulator.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: self.thresholds.as_entire_binding(),
                },
            ],
        })
    }

    /// Draws the bound film into `target` (a view of this pass's format).
    pub fn draw(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        film: &wgpu::BindGroup,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("display"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, film, &[]);
        pass.draw(0..3, 0..1);
    }
}

/// `film` in the kernel's accumulator layout, as far as the display pass reads it: each
/// pixel's count and exact sum (as the even samples' sum, the odd ones' zero).
pub fn accumulator_words(film: &Film) -> Vec<u32> {
    let mut words = vec![0u32; film.pixels.len() * ACCUM_WORDS as usize];
    for (p, px) in film
        .pixels
        .iter()
        .zip(words.chunks_exact_mut(ACCUM_WORDS as usize))
    {
        px[ACCUM_COUNT as usize] = p.n.min(u32::MAX as u64) as u32;
        for (c, sum) in p.sum.iter().enumerate() {
            for w in 0..SUM_WORDS {
                px[ACCUM_EVEN_SUM as usize + 3 * w + c] = sum.word(w);
            }
        }
    }
    words
}

/// An image of `texture` (8-bit RGBA or BGRA, as the display pass draws) as RGB bytes, rows
/// from the top: a screenshot.
pub fn read_texture(ctx: &GpuContext, texture: &wgpu::Texture) -> Result<Vec<u8>, GpuError> {
    let (width, height) = (texture.width(), texture.height());
    let row_bytes = (4 * width).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
        * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("screenshot"),
        size: row_bytes as u64 * height as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &staging,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row_bytes),
                rows_per_image: Some(height),
            },
        },
        texture.size(),
    );
    ctx.queue.submit([encoder.finish()]);
    let bytes = ctx.read_staging(&staging, staging.size(), "the screenshot")?;
    let bgra = matches!(
        texture.format().remove_srgb_suffix(),
        wgpu::TextureFormat::Bgra8Unorm
    );
    let mut rgb = Vec::with_capacity(3 * width as usize * height as usize);
    for row in bytes.chunks_exact(row_bytes as usize) {
        for px in row[..4 * width as usize].chunks_exact(4) {
            if bgra {
                rgb.extend([px[2], px[1], px[0]]);
            } else {
                rgb.extend([px[0], px[1], px[2]]);
            }
        }
    }
    Ok(rgb)
}
