//! `import rtgpu`: rt-gpu from Python. A scene is read as the command line reads it
//! (`rt_gpu::scene::source`), and rendered by the library's render request
//! (`rt_gpu::render::request`), the same code `rt-gpu SCENE` runs: the same options give the same
//! film, and so the same bytes. Renders release the GIL, report progress to an optional
//! callback and stop at Ctrl-C with `KeyboardInterrupt`.

use numpy::{PyArray1, PyArray3, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyKeyboardInterrupt, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyList};
use rt_gpu::film::Film;
use rt_gpu::options::{Backend, DEFAULT_ROULETTE_DEPTH, Integrator, RenderOptions, SamplerKind};
use rt_gpu::render::progressive::Outcome;
use rt_gpu::render::request::{Hooks, Request};
use rt_gpu::render::{GpuChoice, auto_backend};
use rt_gpu::scene::Scene as RtScene;
use rt_gpu::scene::flat::FlatScene;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

/// rt-gpu's one-line message as a `ValueError`.
fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// A scene: read from a file or a built-in name (`load`), or from TOML text (`load_string`).
#[pyclass(module = "rtgpu")]
struct Scene {
    scene: RtScene,
    file: Option<PathBuf>,
}

#[pymethods]
impl Scene {
    /// Its name (the file's stem, or the built-in's).
    #[getter]
    fn name(&self) -> String {
        self.scene.name.clone()
    }

    /// The image size it asks for, (width, height).
    #[getter]
    fn size(&self) -> (u32, u32) {
        (self.scene.defaults.width, self.scene.defaults.height)
    }

    /// Sets the image size a render without `size` gets, (width, height), each at least 1.
    #[setter]
    fn set_size(&mut self, size: (u32, u32)) -> PyResult<()> {
        let (width, height) = size;
        rt_gpu::film::check_image_size(width, height).map_err(value_error)?;
        rt_gpu::film::check_memory(width, height).map_err(value_error)?;
        (self.scene.defaults.width, self.scene.defaults.height) = (width, height);
        Ok(())
    }

    /// The number of path segments a render without `max_depth` follows.
    #[getter]
    fn max_depth(&self) -> u32 {
        self.scene.defaults.max_depth
    }

    #[setter]
    fn set_max_depth(&mut self, max_depth: u32) -> PyResult<()> {
        let most = rt_gpu::scene::file::MAX_DEPTH_LIMIT;
        if !(1..=most).contains(&max_depth) {
            return Err(value_error(format!(
                "max_depth must be in 1..={most}, got {max_depth}"
            )));
        }
        self.scene.defaults.max_depth = max_depth;
        Ok(())
    }

    /// Its punctual lights (points, spots, suns; a glTF file's lamps too), each as a scene
    /// file's `[[light]]` table: `{"point": {"position": [...], "intensity": [...]}}`,
    /// `{"spot": {..., "look_at": [...], "inner": degrees, "outer": degrees}}` or
    /// `{"directional": {"direction": [...], "irradiance": [...]}}`.
    #[getter]
    fn lights<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let out = PyList::empty(py);
        for light in &self.scene.punctual {
            out.append(to_python(
                py,
                &rt_gpu::scene::file::light_table(light).map_err(value_error)?,
            )?)?;
        }
        Ok(out)
    }

    /// Replaces its punctual lights with `lights` (tables as `lights` gives them), each checked
    /// as a scene file's is; `[]` removes them all.
    #[setter]
    fn set_lights(&mut self, lights: &Bound<'_, PyAny>) -> PyResult<()> {
        let mut punctual = Vec::new();
        for (i, light) in lights.try_iter()?.enumerate() {
            let table = from_python(&light?)?;
            punctual.push(
                rt_gpu::scene::file::light_from_table(table)
                    .map_err(|e| value_error(format!("light {i}: {e}")))?,
            );
        }
        self.scene.punctual = punctual;
        Ok(())
    }

    /// Sets parameters of light `index` (its position in `lights`) as its table names them
    /// (`intensity`, `position`, `look_at`, `direction`, `irradiance`, `inner`, `outer`),
    /// checked as a scene file's are: `scene.set_light(0, intensity=[100, 100, 100])`. A spot
    /// given a new `position` alone turns to keep pointing at its `look_at`.
    #[pyo3(signature = (index, **params))]
    fn set_light(&mut self, index: usize, params: Option<&Bound<'_, PyDict>>) -> PyResult<()> {
        let count = self.scene.punctual.len();
        let Some(light) = self.scene.punctual.get(index) else {
            return Err(value_error(format!(
                "no light {index}: the scene has {count} punctual light{}",
                if count == 1 { "" } else { "s" }
            )));
        };
        let mut table = rt_gpu::scene::file::light_table(light).map_err(value_error)?;
        // The one kind's table inside: {"point": {...}}.
        if let (Some(params), Some(toml::Value::Table(kind))) = (
            params,
            table
                .as_table_mut()
                .and_then(|t| t.iter_mut().next().map(|(_, v)| v)),
        ) {
            for (key, value) in params.iter() {
                kind.insert(key.extract()?, from_python(&value)?);
            }
        }
        self.scene.punctual[index] = rt_gpu::scene::file::light_from_table(table)
            .map_err(|e| value_error(format!("light {index}: {e}")))?;
        Ok(())
    }

    /// The names of its materials, in their order.
    #[getter]
    fn materials(&self) -> Vec<String> {
        self.scene.material_names.clone()
    }

    /// The camera, as a dict: look_from, look_at, up (3 numbers each), vfov (degrees),
    /// aperture (lens diameter; 0: a pinhole), focus_distance (None: the look-at point).
    #[getter]
    fn camera<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = &self.scene.camera;
        let out = PyDict::new(py);
        out.set_item("look_from", c.look_from.to_array())?;
        out.set_item("look_at", c.look_at.to_array())?;
        out.set_item("up", c.up.to_array())?;
        out.set_item("vfov", c.vfov_degrees)?;
        out.set_item("aperture", c.aperture)?;
        out.set_item("focus_distance", c.focus_distance)?;
        Ok(out)
    }

    /// Sets the camera from a dict of the keys `camera` gives (those left out keep their
    /// values); checked as a scene file's camera is.
    #[setter]
    fn set_camera(&mut self, camera: &Bound<'_, PyDict>) -> PyResult<()> {
        let mut c = self.scene.camera.clone();
        for (key, value) in camera.iter() {
            let key: String = key.extract()?;
            let vector = |v: &Bound<'_, PyAny>| -> PyResult<glam::Vec3> {
                Ok(glam::Vec3::from_array(v.extract::<[f32; 3]>()?))
            };
            match key.as_str() {
                "look_from" => c.look_from = vector(&value)?,
                "look_at" => c.look_at = vector(&value)?,
                "up" => c.up = vector(&value)?,
                "vfov" => c.vfov_degrees = value.extract()?,
                "aperture" => c.aperture = value.extract()?,
                "focus_distance" => c.focus_distance = value.extract()?,
                other => {
                    return Err(value_error(format!(
                        "camera has no {other:?}: look_from, look_at, up, vfov, aperture, focus_distance"
                    )));
                }
            }
        }
        c.validate().map_err(value_error)?;
        self.scene.camera = c;
        Ok(())
    }

    /// Material `name`'s parameters, as its scene-file table (`type` and the rest).
    fn material<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
        let index = self.material_index(name)?;
        let table = toml::Value::try_from(&self.scene.materials[index]).map_err(value_error)?;
        to_python(py, &table)
    }

    /// Sets parameters of material `name` as its scene-file table names them (`albedo`,
    /// `roughness`, `ior`, `radiance`, ...; `type` too), checked as a scene file's are:
    /// `scene.set_material("light", radiance=[30, 30, 30])`. The next render uses them.
    #[pyo3(signature = (name, **params))]
    fn set_material(&mut self, name: &str, params: Option<&Bound<'_, PyDict>>) -> PyResult<()> {
        let index = self.material_index(name)?;
        let mut table = toml::Value::try_from(&self.scene.materials[index]).map_err(value_error)?;
        // Image paths in the table are the scene file's, relative to its directory.
        let loader = match &self.file {
            Some(file) => rt_gpu::assets::loader::Loader::for_file(file),
            None => rt_gpu::assets::loader::Loader::working_directory(),
        };
        // A material a mesh file made may hold what its table cannot say (glTF's alpha, a
        // texture's sampler, an image inside the file): edited through the table, it would
        // silently lose it.
        let unchanged = loader.during(|| table.clone().try_into::<rt_gpu::scene::Material>());
        if unchanged.ok().as_ref() != Some(&self.scene.materials[index]) {
            return Err(value_error(format!(
                "material \"{name}\" holds what a scene file's table cannot (it came from a mesh file): set_material edits materials a scene file could write"
            )));
        }
        if let (Some(params), toml::Value::Table(t)) = (params, &mut table) {
            for (key, value) in params.iter() {
                t.insert(key.extract()?, from_python(&value)?);
            }
        }
        let material: rt_gpu::scene::Material =
            loader
                .during(|| table.try_into())
                .map_err(|e: toml::de::Error| {
                    value_error(format!("material \"{name}\": {}", e.message()))
                })?;
        material
            .validate()
            .map_err(|e| value_error(format!("material \"{name}\": {e}")))?;
        self.scene.materials[index] = material;
        Ok(())
    }

    /// Notes of what the file asks for and rt-gpu does not do are printed when it loads.
    fn __repr__(&self) -> String {
        let (w, h) = self.size();
        format!(
            "<rtgpu.Scene '{}' {w}x{h}, {} objects>",
            self.scene.name,
            self.scene.objects.len()
        )
    }
}

impl Scene {
    fn material_index(&self, name: &str) -> PyResult<usize> {
        (self.scene.material_names.iter().position(|n| n == name)).ok_or_else(|| {
            value_error(format!(
                "no material {name:?}: the scene has {}",
                self.scene.material_names.join(", ")
            ))
        })
    }
}

/// A TOML value (a material's table) as Python data.
fn to_python<'py>(py: Python<'py>, value: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match value {
        toml::Value::String(s) => s.into_pyobject(py)?.into_any(),
        toml::Value::Integer(i) => i.into_pyobject(py)?.into_any(),
        toml::Value::Float(f) => f.into_pyobject(py)?.into_any(),
        toml::Value::Boolean(b) => b.into_pyobject(py)?.to_owned().into_any(),
        toml::Value::Datetime(d) => d.to_string().into_pyobject(py)?.into_any(),
        toml::Value::Array(items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(to_python(py, item)?)?;
            }
            list.into_any()
        }
        toml::Value::Table(table) => {
            let dict = PyDict::new(py);
            for (k, v) in table {
                dict.set_item(k, to_python(py, v)?)?;
            }
            dict.into_any()
        }
    })
}

/// Python data (numbers, strings, lists, dicts; arrays through `tolist`) as a TOML value.
fn from_python(value: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
    if let Ok(b) = value.cast::<PyBool>() {
        return Ok(toml::Value::Boolean(b.is_true()));
    }
    if let Ok(i) = value.extract::<i64>() {
        return Ok(toml::Value::Integer(i));
    }
    if let Ok(f) = value.extract::<f64>() {
        return Ok(toml::Value::Float(f));
    }
    if let Ok(s) = value.extract::<String>() {
        return Ok(toml::Value::String(s));
    }
    if let Ok(d) = value.cast::<PyDict>() {
        let mut table = toml::Table::new();
        for (k, v) in d.iter() {
            table.insert(k.extract()?, from_python(&v)?);
        }
        return Ok(toml::Value::Table(table));
    }
    if value.hasattr("tolist")? {
        return from_python(&value.call_method0("tolist")?);
    }
    if let Ok(items) = value.try_iter() {
        return Ok(toml::Value::Array(
            items
                .map(|item| from_python(&item?))
                .collect::<PyResult<_>>()?,
        ));
    }
    Err(value_error(format!(
        "cannot use {value} as a scene parameter"
    )))
}

/// A finished render: `image` is linear radiance, float32, (height, width, 3), row 0 at the top
/// (denoised where the render was asked to denoise; `noisy` is then the film's own mean, and
/// `albedo` and `normal` the feature buffers that guided the denoiser).
#[pyclass(module = "rtgpu")]
struct Render {
    film: Film,
    denoised: Option<rt_gpu::render::request::Denoised>,
    /// The files the scene read: `write` never replaces them.
    inputs: Vec<PathBuf>,
    #[pyo3(get)]
    spp: u32,
    #[pyo3(get)]
    backend: String,
    #[pyo3(get)]
    device: String,
    #[pyo3(get)]
    seconds: f64,
}

#[pymethods]
impl Render {
    /// Each pixel's radiance (float32, (height, width, 3)): the film's mean, denoised where
    /// the render was asked to denoise.
    #[getter]
    fn image<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f32>>> {
        match &self.denoised {
            Some(d) => self.array(py, &d.image),
            None => self.array(py, &self.film.mean_rgb()),
        }
    }

    /// The film's mean radiance, not denoised (float32, (height, width, 3)).
    #[getter]
    fn noisy<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f32>>> {
        self.array(py, &self.film.mean_rgb())
    }

    /// With `denoise=True`: the albedo feature buffer (in [0, 1]), else None.
    #[getter]
    fn albedo<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray3<f32>>>> {
        (self.denoised.as_ref())
            .map(|d| self.array(py, &d.features.albedo))
            .transpose()
    }

    /// With `denoise=True`: the normal feature buffer (mean shading normals, in [-1, 1]),
    /// else None.
    #[getter]
    fn normal<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray3<f32>>>> {
        (self.denoised.as_ref())
            .map(|d| self.array(py, &d.features.normal))
            .transpose()
    }

    /// The film's own estimate of the image's RMSE (from its samples' variance).
    #[getter]
    fn estimated_rmse(&self) -> f64 {
        self.film.estimated_rmse()
    }

    /// Writes the image as the command line does: the format by the extension (.png, .ppm,
    /// .exr film file, .pfm), atomically; a denoised render as `--denoise` writes it (an .exr
    /// with the noisy image and the feature buffers as layers).
    fn write(&self, path: PathBuf) -> PyResult<()> {
        let inputs: Vec<&std::path::Path> = self.inputs.iter().map(PathBuf::as_path).collect();
        rt_gpu::film::output::PendingOutput::claim(&path, &inputs)
            .and_then(|pending| match &self.denoised {
                Some(d) => {
                    let image = rt_gpu::render::request::denoised_image(&self.film, d);
                    pending.commit_encoded(None, |format, transfer| image.encode(format, transfer))
                }
                None => pending.commit_image(&self.film, None),
            })
            .map_err(|e| value_error(format!("{e:#}")))
    }

    fn __repr__(&self) -> String {
        format!(
            "<rtgpu.Render {}x{}, {} spp on {} [{}], {:.2} s{}>",
            self.film.width,
            self.film.height,
            self.spp,
            self.backend,
            self.device,
            self.seconds,
            if self.denoised.is_some() {
                ", denoised"
            } else {
                ""
            }
        )
    }
}

impl Render {
    /// `pixels` as a (height, width, 3) float32 array.
    fn array<'py>(
        &self,
        py: Python<'py>,
        pixels: &[[f32; 3]],
    ) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let (w, h) = (self.film.width as usize, self.film.height as usize);
        let flat: Vec<f32> = pixels.iter().flatten().copied().collect();
        PyArray1::from_vec(py, flat).reshape([h, w, 3])
    }
}

/// Reads a scene: a scene file (.toml), a glTF file (.glb, .gltf; `camera`, a name, picks one
/// of its cameras), or a built-in scene's name (`rtgpu.scenes()`). Overrides set what the
/// scene's setters set, in this order: `camera` (a dict), `size`, `max_depth`, `lights` (a
/// list), `materials` (a dict of material name to a dict of parameters):
/// `rtgpu.load("cornell", size=(256, 256), materials={"white": {"albedo": [0.5, 0.5, 0.5]}})`.
#[pyfunction]
#[pyo3(signature = (source, camera = None, **overrides))]
fn load(
    py: Python<'_>,
    source: &str,
    camera: Option<&Bound<'_, PyAny>>,
    overrides: Option<&Bound<'_, PyDict>>,
) -> PyResult<Scene> {
    let picked: Option<String> = match camera {
        Some(c) if !c.is_instance_of::<PyDict>() => Some(c.extract()?),
        _ => None,
    };
    let read = py
        .detach(|| rt_gpu::scene::source::resolve(source, picked.as_deref()))
        .map_err(|e| value_error(format!("{e:#}")))?;
    for note in &read.notes {
        eprintln!("{note}");
    }
    let mut scene = Scene {
        scene: read.scene,
        file: read.file,
    };
    if let Some(view) = camera.and_then(|c| c.cast::<PyDict>().ok()) {
        scene.set_camera(view)?;
    }
    let Some(overrides) = overrides else {
        return Ok(scene);
    };
    const KNOWN: [&str; 4] = ["size", "max_depth", "lights", "materials"];
    for key in overrides.keys() {
        let key: String = key.extract()?;
        if !KNOWN.contains(&key.as_str()) {
            return Err(value_error(format!(
                "load() has no override {key:?}: camera, size, max_depth, lights, materials"
            )));
        }
    }
    if let Some(size) = overrides.get_item("size")? {
        scene.set_size(size.extract()?)?;
    }
    if let Some(depth) = overrides.get_item("max_depth")? {
        scene.set_max_depth(depth.extract()?)?;
    }
    if let Some(lights) = overrides.get_item("lights")? {
        scene.set_lights(&lights)?;
    }
    if let Some(materials) = overrides.get_item("materials")? {
        let materials = materials
            .cast::<PyDict>()
            .map_err(|_| value_error("materials= is a dict of material name to parameters"))?;
        for (name, params) in materials.iter() {
            let params = params
                .cast::<PyDict>()
                .map_err(|_| value_error(format!("materials[{name}] is a dict of parameters")))?;
            scene.set_material(&name.extract::<String>()?, Some(params))?;
        }
    }
    Ok(scene)
}

/// Reads a scene from TOML text (the scene-file syntax; paths relative to the working
/// directory).
#[pyfunction]
#[pyo3(signature = (toml, name = "scene"))]
fn load_string(toml: &str, name: &str) -> PyResult<Scene> {
    let scene = rt_gpu::scene::file::parse(toml, "<string>", name).map_err(value_error)?;
    Ok(Scene { scene, file: None })
}

/// Writes `image` (linear radiance, (height, width, 3), every value finite and >= 0) as the
/// command line writes a render: the format by the extension (.png and .ppm through their
/// transfer curves, .exr, .pfm), atomically.
#[pyfunction]
fn write(py: Python<'_>, path: PathBuf, image: &Bound<'_, PyAny>) -> PyResult<()> {
    let numpy = py.import("numpy")?;
    let array = numpy.call_method1("ascontiguousarray", (image, "float32"))?;
    let Ok(array) = array.cast::<PyArray3<f32>>() else {
        let shape: Vec<usize> = array.getattr("shape")?.extract()?;
        return Err(value_error(format!(
            "an image is (height, width, 3), not {shape:?}"
        )));
    };
    let array = array.readonly();
    let shape = array.shape();
    if shape[2] != 3 {
        return Err(value_error(format!(
            "an image is (height, width, 3), not {shape:?}"
        )));
    }
    let (h, w) = (shape[0], shape[1]);
    rt_gpu::film::check_image_size(w as u32, h as u32).map_err(value_error)?;
    let values = array.as_slice()?;
    let mut film = Film::new(w as u32, h as u32);
    for (i, (pixel, rgb)) in film
        .pixels
        .iter_mut()
        .zip(values.chunks_exact(3))
        .enumerate()
    {
        let value = glam::Vec3::from_slice(rgb);
        if !rt_gpu::film::is_valid_sample(value) {
            return Err(value_error(format!(
                "pixel ({}, {}) is {value}: an image's values are finite and >= 0",
                i % w,
                i / w
            )));
        }
        pixel.add(value);
    }
    rt_gpu::film::output::write_image(&path, &film).map_err(|e| value_error(format!("{e:#}")))
}

/// The built-in scenes' names.
#[pyfunction]
fn scenes() -> Vec<&'static str> {
    rt_gpu::scene::builtin::BUILTINS
        .iter()
        .map(|(n, _)| *n)
        .collect()
}

/// The GPU adapters wgpu sees, by name.
#[pyfunction]
fn devices() -> Vec<String> {
    (rt_gpu::gpu::context::list_adapters().into_iter())
        .map(|info| format!("{} ({:?}, {:?})", info.name, info.device_type, info.backend))
        .collect()
}

/// Renders `scene`: `spp` samples per pixel (or until `time` seconds or the relative error
/// `target_error`), at `size` (width, height; default the scene's), on `backend` ("auto",
/// "cpu" or "gpu"), with `integrator` ("nee", "naive", or the feature buffers "albedo" and
/// "normal") and `sampler` ("sobol" or
/// "independent"); the defaults are the command line's. `progress`, if given, is called with
/// the fraction done. Ctrl-C stops it with `KeyboardInterrupt`. `denoise=True` denoises the
/// image as `--denoise` does (Open Image Denoise; the albedo and normal buffers come back too).
#[pyfunction]
#[pyo3(signature = (scene, spp = None, size = None, seed = 0, backend = "auto", integrator = "nee",
    sampler = "sobol", max_depth = None, time = None, target_error = None, progress = None,
    denoise = false))]
#[allow(clippy::too_many_arguments)]
fn render(
    py: Python<'_>,
    scene: &Scene,
    spp: Option<u32>,
    size: Option<(u32, u32)>,
    seed: u32,
    backend: &str,
    integrator: &str,
    sampler: &str,
    max_depth: Option<u32>,
    time: Option<f64>,
    target_error: Option<f64>,
    progress: Option<Py<PyAny>>,
    denoise: bool,
) -> PyResult<Render> {
    let integrator = match integrator {
        "nee" => Integrator::Nee,
        "naive" => Integrator::Naive,
        "albedo" => Integrator::Albedo,
        "normal" => Integrator::Normal,
        other => {
            return Err(value_error(format!(
                "integrator must be \"nee\", \"naive\", \"albedo\" or \"normal\", not {other:?}"
            )));
        }
    };
    let sampler = match sampler {
        "sobol" => SamplerKind::Sobol,
        "independent" => SamplerKind::Independent,
        other => {
            return Err(value_error(format!(
                "sampler must be \"sobol\" or \"independent\", not {other:?}"
            )));
        }
    };
    // As the command line: 64 spp unless a time or an error target ends the render.
    let spp = match (spp, time.or(target_error)) {
        (Some(0), _) => return Err(value_error("spp must be at least 1")),
        (Some(spp), _) => spp,
        (None, Some(_)) => u32::MAX,
        (None, None) => 64,
    };
    for (what, value) in [("time", time), ("target_error", target_error)] {
        if let Some(x) = value
            && !(x > 0.0 && x.is_finite())
        {
            return Err(value_error(format!(
                "{what} must be a positive number, got {x}"
            )));
        }
    }
    if let Some(d) = max_depth
        && !(1..=rt_gpu::scene::file::MAX_DEPTH_LIMIT).contains(&d)
    {
        return Err(value_error(format!(
            "max_depth must be in 1..={}, got {d}",
            rt_gpu::scene::file::MAX_DEPTH_LIMIT
        )));
    }
    let (width, height) = size.unwrap_or(scene.size());
    rt_gpu::film::check_image_size(width, height).map_err(value_error)?;
    let opts = RenderOptions {
        width,
        height,
        spp,
        first_sample: 0,
        seed,
        max_depth: max_depth.unwrap_or(scene.scene.defaults.max_depth),
        integrator,
        sampler,
        roulette_depth: DEFAULT_ROULETTE_DEPTH,
    };
    let gpu = GpuChoice::default();
    let interrupted = AtomicBool::new(false);
    let finished = py.detach(|| -> anyhow::Result<_> {
        let flat = FlatScene::new(&scene.scene, width, height)?;
        let backend = match backend {
            "cpu" => Backend::Cpu,
            "gpu" => Backend::Gpu,
            "auto" => auto_backend(&gpu, &flat).backend,
            other => anyhow::bail!("backend must be \"auto\", \"cpu\" or \"gpu\", not {other:?}"),
        };
        let request = Request {
            scene: scene.scene.clone(),
            scene_file: scene.file.clone(),
            flat,
            opts,
            backend,
            gpu: gpu.clone(),
            budget: time,
            target_error,
            output: None,
            gamma: None,
            checkpoint: None,
            unspecialised: false,
            // Ctrl-C is looked for between passes: at least once a second.
            pass_seconds: Some(1.0),
            denoise,
        };
        let hooks = Hooks {
            ready: &|| {},
            progress: &|p| {
                if let Some(callback) = &progress {
                    // Of the samples, or of the time where the samples are unlimited.
                    let done = match (time, p.total_spp) {
                        (Some(budget), u32::MAX) => (p.elapsed / budget).min(1.0),
                        _ => p.spp / p.total_spp as f64,
                    };
                    Python::attach(|py| {
                        if let Err(e) = callback.call1(py, (done,)) {
                            e.write_unraisable(py, None);
                        }
                    });
                }
            },
            // Between passes: Python's signal handlers run (Ctrl-C sets the flag).
            stop: &|| {
                let stop = Python::attach(|py| py.check_signals().is_err());
                if stop {
                    interrupted.store(true, Ordering::SeqCst);
                }
                stop
            },
        };
        Ok((request.run(&hooks)?, backend))
    });
    let (finished, backend) = finished.map_err(|e| value_error(format!("{e:#}")))?;
    if interrupted.load(Ordering::SeqCst) && finished.outcome == Outcome::Stopped {
        return Err(PyKeyboardInterrupt::new_err("render stopped"));
    }
    let inputs = (scene.file.iter().cloned())
        .chain(scene.scene.input_paths().map(PathBuf::from))
        .collect();
    Ok(Render {
        inputs,
        spp: finished.done,
        backend: backend.name().to_string(),
        device: finished.rendered.device,
        seconds: finished.seconds,
        film: finished.rendered.film,
        denoised: finished.denoised,
    })
}

#[pymodule]
fn rtgpu(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Scene>()?;
    m.add_class::<Render>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(load_string, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(scenes, m)?)?;
    m.add_function(wrap_pyfunction!(write, m)?)?;
    m.add_function(wrap_pyfunction!(devices, m)?)?;
    Ok(())
}
