//! wgpu plumbing: adapter and device, the compute pipelines of `crates/render/shaders/trace.wgsl`,
//! buffer upload, dispatch and read-back.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec4};
use wgpu::util::DeviceExt;

use super::{GpuError, shader_source};
use crate::field::{Fbm, Field};
use crate::render::camera::Camera;
use crate::render::cpu::RenderSettings;
use crate::render::image::Frame;
use crate::render::material::{DRY_SCALE, VARIATION_SEED};
use crate::render::shade::{AO_SAMPLES, SUN_SEED, Water};
use crate::render::trace::Method;
use crate::tape::Tape;
use crate::tape::noise::encode_fbm;

/// The adapter wgpu picks by default (any backend; lavapipe counts).
fn default_adapter() -> Result<wgpu::Adapter, GpuError> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle());
    pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))
        .map_err(GpuError::NoAdapter)
}

/// An adapter's name and backend, for messages.
fn adapter_name(info: &wgpu::AdapterInfo) -> String {
    format!("{} ({:?})", info.name, info.backend)
}

/// Uniform block of `trace.wgsl` (`struct Uniforms`); see the comments there.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct Uniforms {
    v: [[f32; 4]; 23],
    dims: [u32; 4],
    consts: [u32; 4],
}

/// Bytes of one pixel's saved state (`struct Saved` of `trace.wgsl`).
const SAVED_BYTES: u64 = 8 * 16;
/// Pixels per tile: the saved states of a tile fit one 64 MiB buffer.
const TILE_PIXELS: u64 = 1 << 19;
/// Passes over a tile before giving up (each resumes every unfinished pixel).
const MAX_PASSES: u32 = 100_000;

fn v4(v: Vec3, w: f32) -> [f32; 4] {
    Vec4::new(v.x, v.y, v.z, w).to_array()
}

impl Uniforms {
    fn new(tape: &Tape, cam: &Camera, s: &RenderSettings) -> Self {
        let (right, up, forward, tan_half) = cam.basis();
        let sh = &s.shading;
        let m = &s.materials;
        let b = tape.support();
        let method = match s.trace.method {
            Method::Segment => 0.0,
            Method::Sphere => 1.0,
        };
        let snow = m.snow_line.map_or([0.0; 2], |l| [l.altitude, l.blend]);
        let (disk_u, disk_v) = sh.sun_disk();
        let (water, on) = sh.water.map_or((Water::at(0.0), 0.0), |w| (w, 1.0));
        let (ground_flags, ground_at) = tape.ground.map_or((0, 0), |(f, at)| (f, at + 1));
        Uniforms {
            v: [
                v4(cam.eye, tan_half),
                v4(right, cam.width as f32 / cam.height as f32),
                v4(up, cam.width as f32),
                v4(forward, cam.height as f32),
                v4(b.min, s.trace.epsilon),
                v4(b.max, s.trace.cone),
                [tape.lipschitz(), s.trace.grow, tape.grad_step(), method],
                v4(sh.sun, if sh.shadows { 1.0 } else { 0.0 }),
                v4(sh.sun_color, sh.haze),
                v4(sh.zenith, sh.cave_reach),
                v4(sh.horizon, sh.ao_radius),
                v4(sh.bounce, sh.exposure),
                v4(m.rock, m.rock_slope.0),
                v4(m.soil, m.rock_slope.1),
                v4(m.grass, m.soil_slope.0),
                v4(m.snow, m.soil_slope.1),
                [snow[0], snow[1], m.variation, m.variation_wavelength],
                [m.feature_depth.0, m.feature_depth.1, DRY_SCALE, 0.0],
                v4(m.dry, 0.0),
                v4(disk_u, 0.0),
                v4(disk_v, 0.0),
                [water.level, water.clarity, on, 0.0],
                v4(water.colour, 0.0),
            ],
            dims: [cam.width, cam.height, s.trace.max_steps, ground_at],
            consts: [VARIATION_SEED, AO_SAMPLES, ground_flags, SUN_SEED],
        }
    }
}

/// The `render` and `probe` pipelines compiled for one set of [`Tape::features`].
struct TapePipelines {
    render: wgpu::ComputePipeline,
    probe: wgpu::ComputePipeline,
}

/// An open GPU device with the tracing pipelines, reusable across frames.
pub struct GpuContext {
    device: wgpu::Device,
    queue: wgpu::Queue,
    module: wgpu::ShaderModule,
    /// By [`Tape::features`]: compiled on first use.
    pipelines: Mutex<HashMap<u32, Arc<TapePipelines>>>,
    fbm_probe: wgpu::ComputePipeline,
    /// Name and backend of the adapter, for messages.
    pub adapter: String,
    /// True on a software adapter (lavapipe, which runs the shader on the CPU's cores).
    pub software: bool,
}

impl GpuContext {
    /// The default adapter's name and backend, and whether it is a software one, without
    /// opening a device or compiling the tracer: a cheap look before [`GpuContext::new`].
    pub fn default_adapter() -> Result<(String, bool), GpuError> {
        let info = default_adapter()?.get_info();
        Ok((
            adapter_name(&info),
            info.device_type == wgpu::DeviceType::Cpu,
        ))
    }

    /// Opens the default adapter (any backend; lavapipe counts) and builds the pipelines.
    pub fn new() -> Result<Self, GpuError> {
        let adapter = default_adapter()?;
        let info = adapter.get_info();
        let limits = adapter.limits();
        if limits.max_storage_buffers_per_shader_stage < 10 {
            return Err(GpuError::Unsuitable(format!(
                "{} binds {} storage buffers per stage; the tracer needs 10",
                info.name, limits.max_storage_buffers_per_shader_stage
            )));
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("karstic render"),
            required_limits: limits,
            ..Default::default()
        }))
        .map_err(GpuError::Device)?;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("trace.wgsl"),
            source: wgpu::ShaderSource::Wgsl(shader_source().into()),
        });
        let fbm_probe = pipeline(&device, &module, "fbm_probe", &[]);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Shader(e));
        }
        Ok(GpuContext {
            device,
            queue,
            module,
            pipelines: Mutex::new(HashMap::new()),
            fbm_probe,
            adapter: adapter_name(&info),
            software: info.device_type == wgpu::DeviceType::Cpu,
        })
    }

    /// The pipelines for `tape`'s features, compiled on first use.
    fn pipelines(&self, tape: &Tape) -> Result<Arc<TapePipelines>, GpuError> {
        let key = tape.features();
        let mut map = self.pipelines.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(p) = map.get(&key) {
            return Ok(p.clone());
        }
        let constants = Tape::feature_constants(key);
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let p = Arc::new(TapePipelines {
            render: pipeline(&self.device, &self.module, "render", &constants),
            probe: pipeline(&self.device, &self.module, "probe", &constants),
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Shader(e));
        }
        map.insert(key, p.clone());
        Ok(p)
    }

    fn storage(&self, label: &str, bytes: &[u8]) -> wgpu::Buffer {
        // Empty bindings are invalid: pad to one word.
        let pad = [0u8; 4];
        let contents = if bytes.is_empty() { &pad[..] } else { bytes };
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
    }

    fn output(&self, label: &str, size: u64) -> wgpu::Buffer {
        self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        })
    }

    fn check_size(&self, what: &str, bytes: u64) -> Result<(), GpuError> {
        let max = self.device.limits().max_storage_buffer_binding_size;
        if bytes > max {
            return Err(GpuError::Limits(format!(
                "{what} needs a {bytes}-byte buffer; this GPU binds at most {max} bytes"
            )));
        }
        Ok(())
    }

    /// The tape's buffers, bound at 1, 2, 3, 11 and 12 of `crates/render/shaders/`.
    fn tape_buffers(&self, tape: &Tape) -> Result<[(u32, wgpu::Buffer); 5], GpuError> {
        self.check_size("the tape's parameters", 4 * tape.params.len() as u64)?;
        self.check_size("the tape's heightfields", 4 * tape.heights.len() as u64)?;
        self.check_size("the S-field brick tables", 4 * tape.sf_table.len() as u64)?;
        self.check_size("the S-field samples", 4 * tape.sf_data.len() as u64)?;
        Ok([
            (
                1,
                self.storage("instrs", bytemuck::cast_slice(&tape.instrs)),
            ),
            (
                2,
                self.storage("params", bytemuck::cast_slice(&tape.params)),
            ),
            (
                3,
                self.storage("heights", bytemuck::cast_slice(&tape.heights)),
            ),
            (
                11,
                self.storage("sf_table", bytemuck::cast_slice(&tape.sf_table)),
            ),
            (
                12,
                self.storage("sf_data", bytemuck::cast_slice(&tape.sf_data)),
            ),
        ])
    }

    /// The bind group of `pipeline` with `bindings`.
    fn bind_group(
        &self,
        pipeline: &wgpu::ComputePipeline,
        bindings: &[(u32, &wgpu::Buffer)],
    ) -> wgpu::BindGroup {
        let layout = pipeline.get_bind_group_layout(0);
        let entries: Vec<_> = bindings
            .iter()
            .map(|&(binding, b)| wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            })
            .collect();
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &layout,
            entries: &entries,
        })
    }

    /// Runs one dispatch of `pipeline` and returns the first two words of `counters`
    /// (a `u32` array it counts into).
    fn dispatch(
        &self,
        pipeline: &wgpu::ComputePipeline,
        group: &wgpu::BindGroup,
        groups: (u32, u32),
        counters: &wgpu::Buffer,
    ) -> Result<[u32; 2], GpuError> {
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut enc = self.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups(groups.0, groups.1, 1);
        }
        self.queue.submit([enc.finish()]);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Run(e.into()));
        }
        let out = self.read_back(&[counters])?;
        let words = bytemuck::cast_slice::<u8, u32>(&out[0]);
        Ok([words[0], words[1]])
    }

    /// Copies `buffers` into mappable ones and reads them (after the work submitted).
    fn read_back(&self, buffers: &[&wgpu::Buffer]) -> Result<Vec<Vec<u8>>, GpuError> {
        let reads: Vec<_> = buffers
            .iter()
            .map(|b| {
                self.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("read-back"),
                    size: b.size(),
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            })
            .collect();
        let mut enc = self.device.create_command_encoder(&Default::default());
        for (src, dst) in buffers.iter().zip(&reads) {
            enc.copy_buffer_to_buffer(src, 0, dst, 0, src.size());
        }
        self.queue.submit([enc.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        for r in &reads {
            let tx = tx.clone();
            r.map_async(wgpu::MapMode::Read, .., move |res| {
                let _ = tx.send(res);
            });
        }
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Run(e.into()))?;
        for _ in &reads {
            rx.recv()
                .map_err(|e| GpuError::Run(e.into()))?
                .map_err(|e| GpuError::Run(e.into()))?;
        }
        reads
            .iter()
            .map(|r| {
                let bytes = r
                    .get_mapped_range(..)
                    .map_err(|e| GpuError::Run(e.into()))?
                    .to_vec();
                r.unmap();
                Ok(bytes)
            })
            .collect()
    }

    /// Runs one dispatch of `pipeline` and reads `outputs` back (in order).
    fn run(
        &self,
        pipeline: &wgpu::ComputePipeline,
        bindings: &[(u32, &wgpu::Buffer)],
        outputs: &[&wgpu::Buffer],
        groups: (u32, u32),
    ) -> Result<Vec<Vec<u8>>, GpuError> {
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let group = self.bind_group(pipeline, bindings);
        let mut enc = self.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(groups.0, groups.1, 1);
        }
        self.queue.submit([enc.finish()]);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Run(e.into()));
        }
        self.read_back(outputs)
    }

    /// Renders `tape` through `camera` as [`crate::render::cpu::render`] does on the CPU.
    ///
    /// The image goes in tiles of rows; each tile is dispatched until every pixel is done.
    /// One dispatch finishes them all except on lavapipe, whose invocations stop their
    /// loops after 65,535 iterations: there an interrupted pixel saves its state and the
    /// next dispatch (pass) resumes it (see `budget_left` in `crates/render/shaders/trace.wgsl`).
    pub fn render(
        &self,
        tape: &Tape,
        camera: &Camera,
        settings: &RenderSettings,
    ) -> Result<Frame, GpuError> {
        self.render_in_passes(tape, camera, settings, 0)
    }

    /// [`GpuContext::render`] with at most `evals_per_pass` field evaluations per pixel
    /// and dispatch (0: no limit), the pixels resuming where they stopped: the same image,
    /// in shorter dispatches (a bound on dispatch time, as OS watchdogs on real GPUs want).
    pub fn render_in_passes(
        &self,
        tape: &Tape,
        camera: &Camera,
        settings: &RenderSettings,
        evals_per_pass: u32,
    ) -> Result<Frame, GpuError> {
        if let Some(e) = unsupported(settings) {
            return Err(e);
        }
        let (w, h) = (camera.width, camera.height);
        let n = w as u64 * h as u64;
        self.check_size("the image", 4 * n)?;
        // The materials' terrain travels with the tape's heightfields.
        let grounded;
        let tape = match &settings.materials.ground {
            Some(g) => {
                grounded = tape.clone().with_ground(g)?;
                &grounded
            }
            None => tape,
        };
        let tape_buffers = self.tape_buffers(tape)?;
        let uniforms = self.storage(
            "uniforms",
            bytemuck::bytes_of(&Uniforms::new(tape, camera, settings)),
        );
        let tile_rows = ((TILE_PIXELS / w as u64).max(8) as u32 / 8 * 8).min(h.next_multiple_of(8));
        let saved = self.output("saved", SAVED_BYTES * w as u64 * tile_rows as u64);
        let progress = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("progress"),
            size: 32,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let rgba = self.output("rgba", 4 * n);
        let depth = self.output("depth", 4 * n);
        let steps = self.output("steps", 4 * n);
        let mut bindings: Vec<(u32, &wgpu::Buffer)> =
            tape_buffers.iter().map(|(k, b)| (*k, b)).collect();
        bindings.extend([
            (0, &uniforms),
            (4, &rgba),
            (5, &depth),
            (6, &steps),
            (9, &saved),
            (10, &progress),
        ]);
        let pipelines = self.pipelines(tape)?;
        let group = self.bind_group(&pipelines.render, &bindings);
        for row0 in (0..h).step_by(tile_rows as usize) {
            let rows = tile_rows.min(h - row0);
            for pass in 0.. {
                if pass == MAX_PASSES {
                    return Err(GpuError::Run(
                        format!("rows {row0}.. still unfinished after {MAX_PASSES} passes").into(),
                    ));
                }
                let info = [0, 0, 2, row0, pass, evals_per_pass, 0, 0u32];
                self.queue
                    .write_buffer(&progress, 0, bytemuck::cast_slice(&info));
                let left = self.dispatch(
                    &pipelines.render,
                    &group,
                    (w.div_ceil(8), rows.div_ceil(8)),
                    &progress,
                )?;
                if left[1] > 0 {
                    return Err(GpuError::Limits(format!(
                        "{} pixels cannot evaluate the tape once within this adapter's loop budget ({} instructions)",
                        left[1],
                        tape.instrs.len()
                    )));
                }
                if left[0] == 0 {
                    break;
                }
            }
        }
        let out = self.read_back(&[&rgba, &depth, &steps])?;
        let depth = bytemuck::cast_slice::<u8, f32>(&out[1])
            .iter()
            .map(|&t| if t < 0.0 { f32::INFINITY } else { t })
            .collect();
        Ok(Frame::new(
            w,
            h,
            out[0].clone(),
            depth,
            bytemuck::cast_slice::<u8, u32>(&out[2]).to_vec(),
        ))
    }

    /// Evaluates `tape` at each `(p, r)` on the GPU: `(f(p), Lipschitz bound over B(p, r))`.
    pub fn probe(&self, tape: &Tape, points: &[(Vec3, f32)]) -> Result<Vec<(f32, f32)>, GpuError> {
        let tape_buffers = self.tape_buffers(tape)?;
        let bindings: Vec<(u32, &wgpu::Buffer)> =
            tape_buffers.iter().map(|(k, b)| (*k, b)).collect();
        self.run_probes(&self.pipelines(tape)?.probe, &bindings, points)
    }

    /// Evaluates the turbulence `fbm` at each point on the GPU (`crates/render/shaders/noise.wgsl`), to
    /// compare the port with [`Fbm::value`].
    pub fn probe_fbm(&self, fbm: &Fbm, points: &[Vec3]) -> Result<Vec<f32>, GpuError> {
        let params = self.storage("params", bytemuck::cast_slice(&encode_fbm(0, fbm)));
        let points: Vec<(Vec3, f32)> = points.iter().map(|&p| (p, 0.0)).collect();
        let out = self.run_probes(&self.fbm_probe, &[(2, &params)], &points)?;
        Ok(out.into_iter().map(|v| v.0).collect())
    }

    /// Runs a probe entry point over `points` with the buffers `bound` and reads back its
    /// `vec2` per point.
    fn run_probes(
        &self,
        pipeline: &wgpu::ComputePipeline,
        bound: &[(u32, &wgpu::Buffer)],
        points: &[(Vec3, f32)],
    ) -> Result<Vec<(f32, f32)>, GpuError> {
        if points.is_empty() {
            return Ok(Vec::new());
        }
        let input: Vec<[f32; 4]> = points.iter().map(|&(p, r)| v4(p, r)).collect();
        self.check_size("the probes", 16 * input.len() as u64)?;
        let input = self.storage("probe_in", bytemuck::cast_slice(&input));
        let output = self.output("probe_out", 8 * points.len() as u64);
        let groups = (points.len() as u32).div_ceil(64);
        let max = self.device.limits().max_compute_workgroups_per_dimension;
        if groups > max {
            return Err(GpuError::Limits(format!(
                "{} probes exceed one dispatch",
                points.len()
            )));
        }
        let mut bindings = bound.to_vec();
        bindings.extend([(7, &input), (8, &output)]);
        let out = self.run(pipeline, &bindings, &[&output], (groups, 1))?;
        Ok(bytemuck::cast_slice::<u8, [f32; 2]>(&out[0])
            .iter()
            .map(|v| (v[0], v[1]))
            .collect())
    }
}

/// The compute pipeline of `entry` with the overridable `constants`.
fn pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    entry: &str,
    constants: &[(&str, f64)],
) -> wgpu::ComputePipeline {
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: None,
        module,
        entry_point: Some(entry),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants,
            ..Default::default()
        },
        cache: None,
    })
}

/// Opens a device and renders one frame (see [`GpuContext::render`]).
pub fn render(tape: &Tape, camera: &Camera, settings: &RenderSettings) -> Result<Frame, GpuError> {
    GpuContext::new()?.render(tape, camera, settings)
}

/// Why the GPU tracer cannot draw a picture with `settings`, if it cannot: rock coloured
/// by a geology tree, talus and streams, or plants (the shader has none of them). Asked before any work, so the
/// CPU that draws instead can be given its guides.
pub fn unsupported(settings: &RenderSettings) -> Option<GpuError> {
    if settings.materials.geology.is_some() {
        return Some(GpuError::Unsuitable(
            "the shader has no geology trees, which colour this scene's rock".into(),
        ));
    }
    if settings.materials.top.is_some() {
        return Some(GpuError::Unsuitable(
            "the shader has no raster of talus and streams, which lie on this scene's ground"
                .into(),
        ));
    }
    if settings.vegetation.as_ref().is_some_and(|v| !v.is_empty()) {
        return Some(GpuError::Unsuitable(
            "the shader draws no plants, which stand in this scene's pictures (`--bare` leaves them out)".into(),
        ));
    }
    None
}
