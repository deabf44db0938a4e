//! The figures `bench check` judges. Timings come from the benchmarks
//! themselves, run in this process at tiny sizes with the command lines
//! benchmarks.md documents (each writes its own report beside check.json),
//! then read back; sizes and likeness from the renderers directly; the
//! deadline through the device, as a host drives it.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use anari_library_caveray::device::{DataType, Device, Input, Property, Severity, Status, Subject};
use anari_library_caveray::geometry::RayGen;
use anari_library_caveray::render::shapes::ShapeSet;
use anari_library_caveray::render::simd::Level;
use anari_library_caveray::render::stereo::{paper, HmdStereo};
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{
    ssim, Backend, CpuRenderer, Frame, FrameDesc, RenderSettings, Renderer, Sampling,
};
use anari_library_caveray::scene::Scene;
use clap::Parser;
use glam::{UVec2, Vec3};
use serde_json::Value;

use super::super::raycast::camera;
use crate::scene::{at, protocol_frame, VolumeArgs, PROTOCOL_UNITS};
use crate::Failure;

/// A benchmark's arguments as its command line gives them.
#[derive(Parser)]
struct Line<A: clap::Args> {
    #[command(flatten)]
    args: A,
}

fn args<A: clap::Args>(words: &[&str]) -> Result<A, Failure> {
    Line::<A>::try_parse_from(std::iter::once("caveray").chain(words.iter().copied()))
        .map(|line| line.args)
        .map_err(|e| Failure::Runtime(format!("internal: bench check's command line: {e}")))
}

fn read(path: &Path) -> Result<Value, Failure> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| Failure::Runtime(format!("cannot read {}: {e}", path.display())))?;
    serde_json::from_str(&text).map_err(|e| Failure::Runtime(format!("{}: {e}", path.display())))
}

/// The number at `pointer` (a JSON pointer) of report `v`.
fn num(v: &Value, pointer: &str, report: &str) -> Result<f64, Failure> {
    v.pointer(pointer)
        .and_then(Value::as_f64)
        .ok_or_else(|| Failure::Runtime(format!("internal: {report} has no number at {pointer}")))
}

fn numbers(v: &Value, pointer: &str, report: &str) -> Result<Vec<f64>, Failure> {
    v.pointer(pointer)
        .and_then(Value::as_array)
        .map(|a| a.iter().filter_map(Value::as_f64).collect())
        .ok_or_else(|| Failure::Runtime(format!("internal: {report} has no list at {pointer}")))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

fn say(step: &str) {
    println!("bench check: {step}");
}

/// Every figure, by name.
pub fn all(out: &Path) -> Result<BTreeMap<String, f64>, Failure> {
    let mut figures = BTreeMap::new();
    let path = |name: &str| out.join(name);
    let text = |p: &Path| p.to_string_lossy().into_owned();

    say("Buchacher & Erdt's protocol, re-projected against two passes");
    let file = path("stereo.json");
    super::super::stereo::run(args(&[
        "--volume",
        "cthead",
        "--size",
        "128",
        "--steps",
        "8",
        "--shading",
        "none",
        "--json",
        &text(&file),
    ])?)?;
    stereo(&read(&file)?, &mut figures)?;

    say("the CAVE walk, every wall re-projected and planned");
    let file = path("walk.json");
    super::super::cave_stereo::run(args(&[
        "--scale",
        "0.05",
        "--frames",
        "16",
        "--fastest-of",
        "3",
        "--volume-up",
        "+z",
        "--volume-front",
        "-y",
        "--json",
        &text(&file),
    ])?)?;
    walk(&read(&file)?, &mut figures)?;

    say("ray casting: packets against the scalar reference, skipping on and off, level of detail");
    ray_casting(&mut figures)?;

    say("memory per voxel and per triangle, and the GPU against the CPU");
    renderers(&mut figures)?;

    say("frames with a deadline through the device");
    figures.insert("deadline.worst_age_over_render".into(), deadline()?);
    Ok(figures)
}

fn stereo(v: &Value, figures: &mut BTreeMap<String, f64>) -> Result<(), Failure> {
    let run = "/datasets/0/runs/0";
    let at = |f: &str| format!("{run}/views/{f}");
    let left = numbers(v, &at("t_l_ms"), "stereo.json")?;
    let reproject = numbers(v, &at("reproject_ms"), "stereo.json")?;
    let composite = numbers(v, &at("composite_ms"), "stereo.json")?;
    let pair = left
        .iter()
        .zip(reproject.iter().zip(&composite))
        .map(|(l, (r, c))| (r + c) / l)
        .collect();
    figures.insert("stereo.pair_over_left".into(), median(pair));
    figures.insert(
        "stereo.dssim_max".into(),
        num(v, &format!("{run}/dssim_max"), "stereo.json")?,
    );
    Ok(())
}

fn walk(v: &Value, figures: &mut BTreeMap<String, f64>) -> Result<(), Failure> {
    let frames = v
        .pointer("/timeline")
        .and_then(Value::as_array)
        .ok_or_else(|| Failure::Runtime("internal: walk.json has no timeline".into()))?;
    let front: Vec<f64> = frames
        .iter()
        .flat_map(|f| f["walls"].as_array().into_iter().flatten())
        .filter(|w| w["wall"] == "front")
        .filter_map(|w| Some(w["t_lr_ms"].as_f64()? / w["t_l_ms"].as_f64()?))
        .collect();
    if front.is_empty() {
        return Err(Failure::Runtime(
            "the walk re-projected no frame of the front wall".into(),
        ));
    }
    figures.insert("walk.front_pair_over_left".into(), median(front));
    figures.insert(
        "walk.planned_v".into(),
        num(v, "/speedup_v_planned", "walk.json")?,
    );
    figures.insert("walk.dssim_max".into(), num(v, "/dssim_max", "walk.json")?);
    for wall in v["walls"].as_array().into_iter().flatten() {
        if wall["reprojected"].as_u64().unwrap_or(0) == 0 {
            continue;
        }
        let name = wall["name"].as_str().unwrap_or("?");
        let planned = wall["speedup_v_planned"].as_f64().unwrap_or(f64::NAN);
        figures.insert(format!("walk.planned_v.{name}"), planned);
    }
    Ok(())
}

/// Two ways of rendering the same views, interleaved: each view `REPEAT`
/// times each way, alternating, so that a machine's drift falls on both.
/// Returns the median over the views of the slower way's fastest time
/// over the faster way's (`a`'s over `b`'s), and `b`'s images.
fn interleaved(
    views: &[RayGen],
    mut a: impl FnMut(&RayGen) -> Result<(f64, Frame), Failure>,
    mut b: impl FnMut(&RayGen) -> Result<(f64, Frame), Failure>,
) -> Result<(f64, Vec<Frame>), Failure> {
    const REPEAT: usize = 3;
    let mut ratios = Vec::with_capacity(views.len());
    let mut frames = Vec::with_capacity(views.len());
    for rays in views {
        // A first render of each way warms what it caches (pipelines,
        // copies, the clear-brick grid), untimed.
        a(rays)?;
        let mut last = b(rays)?.1;
        let (mut fastest_a, mut fastest_b) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..REPEAT {
            fastest_a = fastest_a.min(a(rays)?.0);
            let (ms, frame) = b(rays)?;
            fastest_b = fastest_b.min(ms);
            last = frame;
        }
        ratios.push(fastest_a / fastest_b);
        frames.push(last);
    }
    Ok((median(ratios), frames))
}

/// `renderer`'s milliseconds for a frame (the GPU's pass clock, the CPU's
/// wall clock) and the frame.
fn timed(
    renderer: &mut Renderer,
    scene: &Scene,
    rays: &RayGen,
    settings: &RenderSettings,
) -> Result<(f64, Frame), Failure> {
    let runtime = |e: anari_library_caveray::render::RenderError| Failure::Runtime(e.to_string());
    let clock = std::time::Instant::now();
    let frame = renderer
        .render(scene, rays, settings, &FrameDesc::new(rays_size()))
        .map_err(runtime)?;
    let ms = match renderer {
        Renderer::Gpu(g) => g.last_pass_ms(),
        Renderer::Cpu(_) => clock.elapsed().as_secs_f64() * 1e3,
    };
    Ok((ms, frame))
}

/// The ray-casting figures' image size.
fn rays_size() -> UVec2 {
    UVec2::splat(128)
}

/// `n` views of the ray-casting protocol at the figures' size.
fn protocol_views(n: u32) -> Result<Vec<RayGen>, Failure> {
    let size = rays_size();
    let setup = HmdStereo::protocol(size.x, paper::SPAN_PX);
    let radius = setup.radius.unwrap_or(paper::RADIUS_M);
    (0..n).map(|i| camera(i, n, &setup, radius, size)).collect()
}

/// The CPU's packets against its scalar reference (both marching every
/// step), empty-space skipping on both renderers, and level of detail on
/// the GPU, each as two ways of rendering the same views, interleaved.
fn ray_casting(figures: &mut BTreeMap<String, f64>) -> Result<(), Failure> {
    let runtime = |e: anari_library_caveray::render::RenderError| Failure::Runtime(e.to_string());
    let (scene, _) = protocol_scene()?;
    let views = protocol_views(4)?;
    let on = RenderSettings::default();
    let off = RenderSettings {
        skipping: false,
        ..RenderSettings::default()
    };
    let mut packets = Renderer::Cpu(CpuRenderer::new());
    let mut scalar = Renderer::Cpu(CpuRenderer::reference());
    let (ratio, _) = interleaved(
        &views,
        |r| timed(&mut scalar, &scene, r, &off),
        |r| timed(&mut packets, &scene, r, &off),
    )?;
    figures.insert("cpu.packets_over_scalar".into(), ratio);
    // The packets' two widths, where this CPU runs AVX-512 (skipping on,
    // as a host renders).
    let widths = (
        CpuRenderer::with_simd(Level::Avx2),
        CpuRenderer::with_simd(Level::Avx512),
    );
    if let (Some(narrow), Some(wide)) = widths {
        let (mut narrow, mut wide) = (Renderer::Cpu(narrow), Renderer::Cpu(wide));
        let (ratio, _) = interleaved(
            &views,
            |r| timed(&mut narrow, &scene, r, &on),
            |r| timed(&mut wide, &scene, r, &on),
        )?;
        figures.insert("cpu.avx512_over_avx2".into(), ratio);
    }
    let cpu = std::cell::RefCell::new(packets);
    let (ratio, _) = interleaved(
        &views,
        |r| timed(&mut cpu.borrow_mut(), &scene, r, &off),
        |r| timed(&mut cpu.borrow_mut(), &scene, r, &on),
    )?;
    figures.insert("cpu.skipping_speedup".into(), ratio);
    let gpu = std::cell::RefCell::new(Renderer::new(Backend::Gpu).map_err(runtime)?);
    let (ratio, _) = interleaved(
        &views,
        |r| timed(&mut gpu.borrow_mut(), &scene, r, &off),
        |r| timed(&mut gpu.borrow_mut(), &scene, r, &on),
    )?;
    figures.insert("gpu.skipping_speedup".into(), ratio);
    let filtered = RenderSettings {
        sampling: Sampling::Filtered,
        ..RenderSettings::default()
    };
    let lod = RenderSettings {
        level_of_detail: 2.0,
        ..filtered.clone()
    };
    let (ratio, coarse) = interleaved(
        &views,
        |r| timed(&mut gpu.borrow_mut(), &scene, r, &filtered),
        |r| timed(&mut gpu.borrow_mut(), &scene, r, &lod),
    )?;
    figures.insert("gpu.lod_speedup".into(), ratio);
    let (_, exact) = timed(&mut gpu.borrow_mut(), &scene, &views[0], &on)?;
    figures.insert(
        "gpu.lod_ssim".into(),
        ssim(&coarse[0], &exact).map_err(runtime)?,
    );
    // An unstructured field against the grid of the same vertices: the
    // Marschner-Lobb signal on 33^3 vertices, and cut into tetrahedra.
    let (grid, tets) = (
        procedural_scene("marschner-lobb:33")?,
        procedural_scene("tets:33")?,
    );
    let (ratio, _) = interleaved(
        &views,
        |r| timed(&mut cpu.borrow_mut(), &tets, r, &on),
        |r| timed(&mut cpu.borrow_mut(), &grid, r, &on),
    )?;
    figures.insert("cpu.tets_over_grid".into(), ratio);
    let (ratio, _) = interleaved(
        &views,
        |r| timed(&mut gpu.borrow_mut(), &tets, r, &on),
        |r| timed(&mut gpu.borrow_mut(), &grid, r, &on),
    )?;
    figures.insert("gpu.tets_over_grid".into(), ratio);
    Ok(())
}

/// A procedural volume (`volume` as `--volume` takes it) in the ray-casting
/// protocol's place, its longest side the protocol's sphere's diameter.
fn procedural_scene(volume: &str) -> Result<Scene, Failure> {
    let volume: VolumeArgs = args(&["--volume", volume])?;
    let loaded = volume.load()?;
    loaded.placed(
        at(Vec3::ZERO, 2.0 * paper::RADIUS_M as f32 / 3f32.sqrt()),
        &protocol_frame(),
        PROTOCOL_UNITS,
    )
}

/// The CT head in the ray-casting protocol's place, and its isosurface.
fn protocol_scene() -> Result<(Scene, Scene), Failure> {
    let volume: VolumeArgs = args(&["--volume", "cthead", "--mesh", "0.6", "--mesh-stride", "4"])?;
    let loaded = volume.load()?.with_stored_axes();
    let (lo, hi) = loaded.bounds();
    let extent = hi - lo;
    let size = extent.max_element() * (2.0 * paper::RADIUS_M as f32) / extent.length();
    let mixed = loaded.placed(at(Vec3::ZERO, size), &protocol_frame(), PROTOCOL_UNITS)?;
    let runtime = |e: anari_library_caveray::scene::SceneError| Failure::Runtime(e.to_string());
    let mesh = Scene::of_shapes(mixed.shapes().to_vec()).map_err(runtime)?;
    let volume = Scene::placed(mixed.volumes().to_vec()).map_err(runtime)?;
    Ok((volume, mesh))
}

/// Bytes per voxel on each renderer, bytes per triangle as each traces a
/// mesh, and the GPU's image against the CPU's.
fn renderers(figures: &mut BTreeMap<String, f64>) -> Result<(), Failure> {
    let runtime = |e: anari_library_caveray::render::RenderError| Failure::Runtime(e.to_string());
    let (volume, mesh) = protocol_scene()?;
    let rays = protocol_views(4)?.swap_remove(1);
    let voxels = volume.volumes()[0]
        .volume
        .dims()
        .as_u64vec3()
        .element_product() as f64;
    let mut frames = Vec::new();
    for (name, mut renderer) in [
        ("cpu", Renderer::Cpu(CpuRenderer::new())),
        ("gpu", Renderer::new(Backend::Gpu).map_err(runtime)?),
    ] {
        let frame = renderer
            .render(
                &volume,
                &rays,
                &RenderSettings::default(),
                &FrameDesc::new(rays_size()),
            )
            .map_err(runtime)?;
        let held = renderer.resident_bytes(&volume);
        figures.insert(
            format!("memory.{name}_bytes_per_voxel"),
            (held.host + held.gpu) as f64 / voxels,
        );
        frames.push(frame);
    }
    figures.insert(
        "gpu_cpu.ssim".into(),
        ssim(&frames[1], &frames[0]).map_err(runtime)?,
    );
    let shapes = mesh.shapes();
    let triangles: usize = shapes.iter().map(|s| s.shape.len()).sum();
    let traced = ShapeSet::build(shapes).map_err(runtime)?;
    let own: u64 = shapes.iter().map(|s| s.shape.heap_bytes()).sum();
    figures.insert(
        "memory.cpu_bytes_per_triangle".into(),
        (own + traced.heap_bytes()) as f64 / triangles as f64,
    );
    let packed = ShapeSet::packed(shapes).map_err(runtime)?;
    let gpu = 16 * (packed.words.len() + packed.shading.len());
    figures.insert(
        "memory.gpu_bytes_per_triangle".into(),
        gpu as f64 / triangles as f64,
    );
    let binary = ShapeSet::build_binary(shapes).map_err(runtime)?;
    figures.insert("cpu.wide_over_binary".into(), traversals(&binary, &traced)?);
    figures.insert(
        "cpu.surface_packets_speedup".into(),
        packet_speedup(&traced)?,
    );
    Ok(())
}

/// The camera rays' first surfaces found one by one and in packets of
/// neighbours (the protocol's four views, each way four times,
/// interleaved, on one thread): the single rays' fastest time over the
/// packets', median over the views. Both must find hits at the same
/// distances.
fn packet_speedup(set: &ShapeSet) -> Result<f64, Failure> {
    let size = rays_size();
    let (w, h) = (size.x as usize, size.y as usize);
    let mut ratios = Vec::new();
    for rays in protocol_views(4)? {
        let single = || {
            let clock = std::time::Instant::now();
            let mut hits = Vec::with_capacity(w * h);
            for y in 0..size.y {
                for x in 0..size.x {
                    let (o, d) = rays.pixel_ray(x, y);
                    hits.push(set.hit(o, d, rays.t_near, rays.t_far).map(|h| h.t));
                }
            }
            (clock.elapsed().as_secs_f64(), hits)
        };
        let packets = || {
            let clock = std::time::Instant::now();
            let hits = set.camera_hits(&rays, (0, 0), (w, h));
            let elapsed = clock.elapsed().as_secs_f64();
            (
                elapsed,
                hits.iter().map(|h| h.map(|h| h.t)).collect::<Vec<_>>(),
            )
        };
        let (mut fastest_single, mut fastest_packets) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..4 {
            let (ts, hits_single) = single();
            let (tp, hits_packets) = packets();
            if hits_single != hits_packets {
                return Err(Failure::Runtime(
                    "packets of camera rays found other hits than the rays one by one".into(),
                ));
            }
            fastest_single = fastest_single.min(ts);
            fastest_packets = fastest_packets.min(tp);
        }
        ratios.push(fastest_single / fastest_packets);
    }
    Ok(median(ratios))
}

/// The same rays' nearest hits in two shape sets (the protocol's four
/// views, each set four times, interleaved, on one thread): `a`'s fastest
/// time over `b`'s, median over the views. Both must find the same hits.
fn traversals(a: &ShapeSet, b: &ShapeSet) -> Result<f64, Failure> {
    let size = rays_size();
    let mut ratios = Vec::new();
    for rays in protocol_views(4)? {
        let trace = |set: &ShapeSet| {
            let clock = std::time::Instant::now();
            let mut hits = Vec::with_capacity((size.x * size.y) as usize);
            for y in 0..size.y {
                for x in 0..size.x {
                    let (o, d) = rays.pixel_ray(x, y);
                    hits.push(set.hit(o, d, rays.t_near, rays.t_far).map(|h| h.t));
                }
            }
            (clock.elapsed().as_secs_f64(), hits)
        };
        let (mut fastest_a, mut fastest_b) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..4 {
            let (ta, hits_a) = trace(a);
            let (tb, hits_b) = trace(b);
            if hits_a != hits_b {
                return Err(Failure::Runtime(
                    "the two BVHs found different hits for the same rays".into(),
                ));
            }
            (fastest_a, fastest_b) = (fastest_a.min(ta), fastest_b.min(tb));
        }
        ratios.push(fastest_a / fastest_b);
    }
    Ok(median(ratios))
}

/// The value's bytes, as a host passes them.
fn bytes<T: bytemuck::Pod>(values: &[T]) -> Vec<u8> {
    bytemuck::cast_slice(values).to_vec()
}

/// Frames with a deadline while the camera moves, as a tracked display's
/// host renders them, one a refresh of a 90 Hz display (the CPU device,
/// ambient occlusion on a 32³ ball, so that a whole render takes many
/// refreshes): the oldest image shown, over the time of one whole render
/// of the same view.
fn deadline() -> Result<f64, Failure> {
    const N: u32 = 32;
    const SIZE: u32 = 128;
    const FRAMES: u32 = 120;
    let errors: Arc<std::sync::Mutex<Vec<String>>> = Default::default();
    let said = errors.clone();
    let mut d = Device::new(Arc::new(move |s: Status| {
        if (s.severity as i32) <= Severity::Warning as i32 {
            if let Ok(mut e) = said.lock() {
                e.push(s.message);
            }
        }
    }));
    d.set_param(Subject::Device, "backend", Input::String("cpu".into()));
    d.commit(Subject::Device);
    let set = |d: &mut Device, o: u64, name: &str, ty: DataType, value: Vec<u8>| {
        d.set_param(Subject::Object(o), name, Input::Bytes(ty, value));
    };
    let object = |d: &mut Device, o: u64, name: &str, ty: DataType, h: u64| {
        d.set_param(Subject::Object(o), name, Input::Object(ty, h));
    };
    let at = |i: u32| 2.0 * i as f32 / (N - 1) as f32 - 1.0;
    let mut voxels = Vec::with_capacity((N * N * N) as usize);
    for z in 0..N {
        for y in 0..N {
            for x in 0..N {
                let r = (at(x) * at(x) + at(y) * at(y) + at(z) * at(z)).sqrt();
                voxels.push((1.0 - r).max(0.0));
            }
        }
    }
    let array = |d: &mut Device, kind, element: DataType, dims: [u64; 3], data: &[u8]| {
        let a = d
            .new_array(kind, element as i32, dims, None)
            .map_err(|_| Failure::Runtime("bench check: the device refused an array".into()))?;
        let ptr = d.map_array(a);
        if ptr.is_null() {
            return Err(Failure::Runtime("bench check: an array did not map".into()));
        }
        // SAFETY: the device allocated dims times the element's size, which
        // is data's length.
        unsafe { std::ptr::copy_nonoverlapping(data.as_ptr(), ptr, data.len()) };
        d.unmap_array(a);
        Ok(a)
    };
    let data = array(
        &mut d,
        DataType::ARRAY3D,
        DataType::FLOAT32,
        [u64::from(N); 3],
        &bytes(&voxels),
    )?;
    let field = d.new_object(DataType::SPATIAL_FIELD, "structuredRegular");
    object(&mut d, field, "data", DataType::ARRAY3D, data);
    set(
        &mut d,
        field,
        "origin",
        DataType::FLOAT32_VEC3,
        bytes(&[-1.0f32; 3]),
    );
    set(
        &mut d,
        field,
        "spacing",
        DataType::FLOAT32_VEC3,
        bytes(&[2.0 / (N - 1) as f32; 3]),
    );
    d.commit(Subject::Object(field));
    let volume = d.new_object(DataType::VOLUME, "transferFunction1D");
    object(&mut d, volume, "value", DataType::SPATIAL_FIELD, field);
    set(
        &mut d,
        volume,
        "opacity",
        DataType::FLOAT32,
        bytes(&[0.3f32]),
    );
    d.commit(Subject::Object(volume));
    let list = array(
        &mut d,
        DataType::ARRAY1D,
        DataType::VOLUME,
        [1, 1, 1],
        &bytes(&[volume as usize]),
    )?;
    let world = d.new_object(DataType::WORLD, "");
    object(&mut d, world, "volume", DataType::ARRAY1D, list);
    d.commit(Subject::Object(world));
    let renderer = d.new_object(DataType::RENDERER, "default");
    d.set_param(
        Subject::Object(renderer),
        "shading",
        Input::String("ao".into()),
    );
    d.commit(Subject::Object(renderer));
    let camera = d.new_object(DataType::CAMERA, "perspective");
    let frame = d.new_object(DataType::FRAME, "");
    set(
        &mut d,
        frame,
        "size",
        DataType::UINT32_VEC2,
        bytes(&[SIZE, SIZE]),
    );
    set(
        &mut d,
        frame,
        "channel.color",
        DataType::DATA_TYPE,
        bytes(&[DataType::UFIXED8_VEC4 as i32]),
    );
    object(&mut d, frame, "world", DataType::WORLD, world);
    object(&mut d, frame, "renderer", DataType::RENDERER, renderer);
    object(&mut d, frame, "camera", DataType::CAMERA, camera);
    let look_from = |d: &mut Device, x: f32| {
        set(
            d,
            camera,
            "position",
            DataType::FLOAT32_VEC3,
            bytes(&[x, 0.0, 3.0]),
        );
        d.commit(Subject::Object(camera));
    };
    let render = |d: &mut Device| {
        d.render_frame(frame, None);
        d.map_frame(frame, "channel.color").ok_or_else(|| {
            Failure::Runtime("bench check: a deadline frame did not render".into())
        })?;
        d.unmap_frame(frame, "channel.color");
        Ok::<_, Failure>(())
    };
    let property = |d: &mut Device, name: &str| match d.property(Subject::Object(frame), name, true)
    {
        Some(Property::Float32(x)) => Ok(f64::from(x)),
        _ => Err(Failure::Runtime(format!(
            "bench check: the frame has no {name}"
        ))),
    };

    // A whole render of the middle view: the median of three.
    d.commit(Subject::Object(frame));
    look_from(&mut d, 0.0);
    let mut whole = Vec::new();
    for _ in 0..3 {
        render(&mut d)?;
        whole.push(1e3 * property(&mut d, "duration")?);
        // The same view again would be the unchanged frame's shortcut.
        look_from(&mut d, whole.len() as f32 * 1e-4);
    }
    let whole = median(whole);

    set(
        &mut d,
        frame,
        "caveray.deadline",
        DataType::FLOAT32,
        bytes(&[8.0f32]),
    );
    d.set_param(
        Subject::Object(frame),
        "caveray.warp",
        Input::String("quad".into()),
    );
    d.commit(Subject::Object(frame));
    // One frame a refresh of a 90 Hz display.
    let period = std::time::Duration::from_secs_f64(1.0 / 90.0);
    let start = std::time::Instant::now();
    let mut ages = Vec::new();
    for i in 0..FRAMES {
        let due = start + period * i;
        std::thread::sleep(due.saturating_duration_since(std::time::Instant::now()));
        look_from(&mut d, -0.4 + 0.8 * i as f32 / FRAMES as f32);
        render(&mut d)?;
        // Negative until the first image is done (the background shows).
        let age = property(&mut d, "caveray.imageAge")?;
        if age >= 0.0 {
            ages.push(age);
        }
    }
    for h in [frame, camera, renderer, world, list, volume, field, data] {
        d.release(h);
    }
    let said = errors.lock().map(|e| e.clone()).unwrap_or_default();
    if !said.is_empty() {
        return Err(Failure::Runtime(format!(
            "bench check: the device said: {}",
            said.join("; ")
        )));
    }
    let Some(worst) = ages.iter().copied().reduce(f64::max) else {
        return Err(Failure::Runtime(format!(
            "bench check: {FRAMES} frames with a deadline showed no image (a whole render takes {whole:.1} ms)"
        )));
    };
    println!(
        "bench check: whole render {whole:.1} ms; {} of {FRAMES} deadline frames showed an image, the oldest {worst:.1} ms old",
        ages.len()
    );
    Ok(worst / whole)
}
