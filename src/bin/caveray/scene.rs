//! The volume and transfer function a command renders, from its flags.

use std::path::{Path, PathBuf};

use anari_library_caveray::cave::{HeadFrame, ScenePlacement};
use anari_library_caveray::data::{
    concentric_shells, is_hdf5, is_vtk_mesh, isosurface_mesh, load_paraview, load_raw,
    load_volume_file, load_vtk_mesh, marschner_lobb, preset, refined, shepp_logan, smooth_waves,
    solid_box, tetrahedra, DataError, Manifest, Orientation, VolumeFormat, VoxelType,
};
use anari_library_caveray::geometry::{Units, VolumeAxis};
use anari_library_caveray::scene::{
    transformed_box, AlphaMode, ColorSource, Kept, ObjectIds, OpacitySource, PlacedShape,
    PlacedVolume, Scene, Shape, ShapeInput, SpatialField, StructuredVolume, SurfaceMaterial,
    TransferFunction,
};
use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::Args;
use glam::{DVec3, UVec3};

use crate::{triple, Failure};

/// Procedural volumes' default size per side.
const PROCEDURAL_SIZE: u32 = 128;
/// Where the project's real volumes sit, beside a checkout.
const SHARED_MANIFEST: &str = "../shared/data/volumes/volumes.toml";

#[derive(Args, Clone)]
pub struct VolumeArgs {
    /// phantom[:N], shells[:N], marschner-lobb[:N], box[:N], tets[:N] (Marschner-Lobb
    /// on N^3 vertices cut into 6 (N-1)^3 tetrahedra), a name from volumes.toml, a
    /// file with a header (NIfTI, NRRD, MetaImage, VTK image data), a VTK unstructured
    /// grid (.vtu, .vtk), a DICOM series' folder, or a raw file (then --dims is
    /// required). Default: the phantom.
    #[arg(long)]
    volume: Option<String>,
    /// The point or cell array of a VTK unstructured grid to render (default: its
    /// first point array, else its first cell array).
    #[arg(long)]
    array: Option<String>,
    /// The grid of a NanoVDB file (.nvdb) to render, by name (default: its first).
    #[arg(long)]
    grid: Option<String>,
    /// Raw file dimensions X,Y,Z.
    #[arg(long, value_parser = dims)]
    dims: Option<UVec3>,
    /// Raw file voxel type.
    #[arg(long, default_value = "u8", value_parser = ["u8", "u16", "f32", "uint8", "uint16", "float32"])]
    dtype: String,
    /// Raw file voxel spacing X,Y,Z.
    #[arg(long, value_parser = triple)]
    spacing: Option<glam::DVec3>,
    /// volumes.toml to look names up in (default: $CAVERAY_DATA/volumes.toml,
    /// else ../shared/data/volumes/volumes.toml).
    #[arg(long)]
    manifest: Option<PathBuf>,
    /// Transfer function: a preset (phantom, ct-skin-bone, ct-bone, mri,
    /// grey, shells, level-set) or a ParaView color map exported as JSON.
    #[arg(long)]
    tf: Option<String>,
    #[command(flatten)]
    placement: PlacementArgs,
    #[command(flatten)]
    mesh: MeshArgs,
}

/// A triangle mesh beside the volume: its own isosurface, as a host that
/// extracts one would send it.
#[derive(Args, Clone, Copy)]
pub struct MeshArgs {
    /// Also draw the volume's isosurface at this fraction of its value
    /// range (0: its smallest value, 1: its largest) as a triangle mesh.
    #[arg(long, value_parser = fraction)]
    mesh: Option<f32>,
    /// The mesh's cells, in voxels per side (2: about a quarter of the
    /// triangles).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=64))]
    mesh_stride: u32,
    /// The mesh's color R,G,B (linear, 0 to 1).
    #[arg(long, default_value = "0.9,0.85,0.75", value_parser = triple)]
    mesh_color: glam::DVec3,
    /// The mesh's opacity: below 1 it is composited with the volume behind.
    #[arg(long, default_value_t = 1.0, value_parser = fraction)]
    mesh_opacity: f32,
}

/// The most triangles `--mesh` extracts.
const MAX_MESH_TRIANGLES: usize = 1 << 24;

fn fraction(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(x) if (0.0..=1.0).contains(&x) => Ok(x),
        _ => Err(format!("expected a number from 0 to 1, got '{s}'")),
    }
}

/// Where the volume goes and which way up; each unset part is the
/// command's default (a rig's `[scene]`).
#[derive(Args, Clone, Copy)]
pub struct PlacementArgs {
    /// Centre of the volume's bounding box X,Y,Z, in the rig's units.
    #[arg(long, value_parser = triple, allow_hyphen_values = true)]
    volume_centre: Option<DVec3>,
    /// Longest side of the volume's bounding box, in the rig's units.
    #[arg(long, value_parser = positive, conflicts_with = "volume_units")]
    volume_size: Option<f64>,
    /// Show the volume at its own size: the unit (mm or m) of data whose
    /// file does not state one (a file that does is taken in its own).
    #[arg(long, value_parser = units)]
    volume_units: Option<Units>,
    /// The volume axis that points up, along the viewer's up (a CT series
    /// stored crown first wants -z).
    #[arg(long, value_parser = axis(), allow_hyphen_values = true)]
    volume_up: Option<VolumeAxis>,
    /// The volume axis that faces a viewer at rest (against the viewer's
    /// forward).
    #[arg(long, value_parser = axis(), allow_hyphen_values = true)]
    volume_front: Option<VolumeAxis>,
}

impl PlacementArgs {
    /// `default` with the parts given on the command line in its place.
    /// The axes come from the command line, else from the data set itself
    /// (`data`), else from `default` (a rig's `[scene]`).
    pub fn over(
        &self,
        default: ScenePlacement,
        data: Orientation,
    ) -> Result<ScenePlacement, Failure> {
        let pick = |cli: Option<VolumeAxis>, data: Option<VolumeAxis>, rig: Option<VolumeAxis>| {
            cli.map(|a| (a, "--volume-"))
                .or(data.map(|a| (a, "the data set's ")))
                .or(rig.map(|a| (a, "the rig's scene.volume_")))
        };
        let up = pick(self.volume_up, data.up, default.up);
        let front = pick(self.volume_front, data.front, default.front);
        let placement = ScenePlacement {
            centre: self.volume_centre.unwrap_or(default.centre),
            size: self.volume_size.unwrap_or(default.size),
            // The command line's size or units take the place of the rig's.
            life_size: match (self.volume_size, self.volume_units) {
                (Some(_), _) => None,
                (None, Some(u)) => Some(u),
                (None, None) => default.life_size,
            },
            up: up.map(|(a, _)| a),
            front: front.map(|(a, _)| a),
        };
        ScenePlacement::check_axes(placement.up, placement.front).map_err(|e| {
            let from = |p: Option<(VolumeAxis, &'static str)>| p.map_or("", |(_, s)| s);
            Failure::Usage(format!("{e} ({}up, {}front)", from(up), from(front)))
        })?;
        Ok(placement)
    }
}

fn axis() -> impl TypedValueParser<Value = VolumeAxis> {
    PossibleValuesParser::new(VolumeAxis::NAMES).try_map(|s| s.parse::<VolumeAxis>())
}

fn units(s: &str) -> Result<Units, String> {
    match s.trim() {
        "mm" => Ok(Units::Millimetres),
        "m" => Ok(Units::Metres),
        _ => Err(format!("expected mm or m, got '{s}'")),
    }
}

fn positive(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x > 0.0 && (x as f32).is_finite() => Ok(x),
        _ => Err(format!("expected a finite number > 0, got '{s}'")),
    }
}

fn dims(s: &str) -> Result<UVec3, String> {
    let v: Vec<u32> = s
        .split(',')
        .map(|p| p.trim().parse())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected three whole numbers X,Y,Z, got '{s}'"))?;
    match v[..] {
        [x, y, z] => Ok(UVec3::new(x, y, z)),
        _ => Err(format!("expected three whole numbers X,Y,Z, got '{s}'")),
    }
}

/// A loaded volume with the transfer function that suits it, not yet placed.
pub struct Loaded {
    pub name: String,
    pub volume: SpatialField,
    /// Where a file with a placement (NIfTI, NRRD) puts its voxels: voxel index
    /// to the file's world, in its units. None: `volume`'s own grid.
    pub index_to_file: Option<glam::Mat4>,
    /// Metres a unit of the file's world, where its header says.
    metres_per_unit: Option<f64>,
    tf: TransferFunction,
    /// The preset's name or the ParaView file `tf` came from.
    tf_name: String,
    /// Presets span the data's range; a ParaView map keeps its own.
    stretch_tf: bool,
    placement: PlacementArgs,
    /// Which way up the data set says it is.
    orientation: Orientation,
    mesh: MeshArgs,
}

impl VolumeArgs {
    /// `--volume` read as a comma-separated list, or `default`'s.
    pub fn volume_list(&self, default: &str) -> Vec<String> {
        self.volume
            .as_deref()
            .unwrap_or(default)
            .split(',')
            .map(|v| v.trim().to_string())
            .filter(|v| !v.is_empty())
            .collect()
    }

    /// Whether `--mesh` asks for a mesh beside the volume.
    pub fn has_mesh(&self) -> bool {
        self.mesh.mesh.is_some()
    }

    /// These arguments with another volume (for commands that sweep several).
    pub fn with_volume(&self, spec: &str) -> Self {
        Self {
            volume: Some(spec.to_string()),
            ..self.clone()
        }
    }

    pub fn load(&self) -> Result<Loaded, Failure> {
        let usage = |e: &dyn std::fmt::Display| Failure::Usage(e.to_string());
        let spec = self.volume.as_deref().unwrap_or("phantom");
        let mut index_to_file = None;
        let mut metres_per_unit = None;
        if self.array.is_some() && !Path::new(spec).is_file() {
            return Err(Failure::Usage(format!(
                "--array names an array of a VTK unstructured grid or a variable of a FLASH file; '{spec}' is neither"
            )));
        }
        if self.grid.is_some() && !is_nvdb_file(Path::new(spec)) {
            return Err(Failure::Usage(format!(
                "--grid names a grid of a NanoVDB file; '{spec}' is not one"
            )));
        }
        let (name, volume, default_tf, orientation) = if let Some((name, volume)) =
            procedural(spec)?
        {
            let tf = if name.starts_with("shells") {
                "shells"
            } else {
                "phantom"
            };
            (name, volume, tf, Orientation::UNKNOWN)
        } else if is_nvdb_file(Path::new(spec)) {
            if self.has_mesh() {
                return Err(Failure::Usage(
                    "--mesh draws a structured grid's isosurface; a NanoVDB grid has none here"
                        .into(),
                ));
            }
            let file =
                anari_library_caveray::data::load_nvdb(Path::new(spec), self.grid.as_deref())
                    .map_err(|e| usage(&e))?;
            // Placed by its own index-to-world map.
            index_to_file = Some(glam::Mat4::IDENTITY);
            let tf = if file.grid.class_name() == "LevelSet" {
                "level-set"
            } else {
                "shells"
            };
            (
                format!("{}:{}", file_stem(spec), file.name),
                SpatialField::from(file.grid),
                tf,
                Orientation::UNKNOWN,
            )
        } else if is_hdf5_file(Path::new(spec)) {
            if self.has_mesh() {
                return Err(Failure::Usage(
                    "--mesh draws a structured grid's isosurface; an AMR field has none here"
                        .into(),
                ));
            }
            // Placed by its own origin and spacing, as a mesh by its
            // positions.
            index_to_file = Some(glam::Mat4::IDENTITY);
            (
                file_stem(spec),
                SpatialField::from(load_flash_file(spec, self.array.as_deref())?),
                "grey",
                Orientation::UNKNOWN,
            )
        } else if is_mesh_file(Path::new(spec)) {
            if self.has_mesh() {
                return Err(Failure::Usage(
                    "--mesh draws a structured grid's isosurface; an unstructured grid has none here"
                        .into(),
                ));
            }
            let file =
                load_vtk_mesh(Path::new(spec), self.array.as_deref()).map_err(|e| usage(&e))?;
            // A mesh is placed by its transform, as a file's own map
            // places a grid: its cells are not moved.
            index_to_file = Some(glam::Mat4::IDENTITY);
            (
                file_stem(spec),
                SpatialField::from(file.mesh),
                "grey",
                Orientation::UNKNOWN,
            )
        } else if let Some(format) = VolumeFormat::of(Path::new(spec)).filter(|f| f.readable()) {
            if self.dims.is_some() {
                return Err(Failure::Usage(format!(
                    "{spec} is a {} {}, whose header gives its size, type and spacing \
                     (--dims, --dtype and --spacing describe raw files only)",
                    format.name(),
                    if format == VolumeFormat::DicomSeries {
                        "series"
                    } else {
                        "file"
                    }
                )));
            }
            let file = load_volume_file(Path::new(spec)).map_err(|e| usage(&e))?;
            index_to_file = Some(file.transform());
            metres_per_unit = file.metres_per_unit();
            let tf = match file.dtype {
                // Hounsfield units: signed CT.
                "int16" => "ct-skin-bone",
                _ => "grey",
            };
            // Anatomical spaces are read as RAS+: superior up, the
            // anterior (the face) toward the viewer.
            let orientation = if file.anatomical {
                Orientation {
                    up: Some(VolumeAxis::PosZ),
                    front: Some(VolumeAxis::PosY),
                }
            } else {
                Orientation::UNKNOWN
            };
            (file_stem(spec), file.volume.into(), tf, orientation)
        } else if VolumeFormat::of(Path::new(spec)) == Some(VolumeFormat::Gzip) {
            return Err(Failure::Usage(gzipped(spec, self.dims.is_some())));
        } else if self.dims.is_some() || Path::new(spec).is_file() {
            let dims = self.dims.ok_or_else(|| {
                Failure::Usage(format!(
                    "{spec} is a raw file: give its size with --dims X,Y,Z (and --dtype, --spacing)"
                ))
            })?;
            let dtype = VoxelType::parse(&self.dtype).map_err(|e| usage(&e))?;
            let spacing = self.spacing.unwrap_or(glam::DVec3::ONE).as_vec3();
            let volume = load_raw(Path::new(spec), dims, dtype, spacing).map_err(|e| usage(&e))?;
            (file_stem(spec), volume.into(), "grey", Orientation::UNKNOWN)
        } else {
            let manifest =
                Manifest::locate(self.manifest.as_deref(), &[PathBuf::from(SHARED_MANIFEST)])
                    .map_err(|e| unknown_volume(spec, &e))?;
            let entry = manifest.find(spec).map_err(|e| unknown_volume(spec, &e))?;
            let tf = match entry.category.as_str() {
                "CT" => "ct-skin-bone",
                "MRI" => "mri",
                _ => "phantom",
            };
            let volume = manifest
                .load_volume(spec)
                .map_err(|e| Failure::Runtime(e.to_string()))?;
            (spec.to_string(), volume.into(), tf, entry.orientation())
        };
        let tf_spec = self.tf.as_deref().unwrap_or(default_tf);
        let (tf, stretch_tf) = transfer_function(tf_spec, &volume)?;
        Ok(Loaded {
            name,
            volume,
            index_to_file,
            metres_per_unit,
            tf,
            tf_name: tf_spec.to_string(),
            stretch_tf,
            placement: self.placement,
            orientation,
            mesh: self.mesh,
        })
    }
}

/// The transfer function `spec` names for `volume`: a ParaView map file
/// (kept over its own range) or a preset (stretched over the data's range,
/// the `bool`).
fn transfer_function(
    spec: &str,
    volume: &SpatialField,
) -> Result<(TransferFunction, bool), Failure> {
    let usage = |e: &dyn std::fmt::Display| Failure::Usage(e.to_string());
    if !Path::new(spec).is_file() {
        return Ok((preset(spec).map_err(|e| usage(&e))?, true));
    }
    let tf = load_paraview(Path::new(spec)).map_err(|e| usage(&e))?;
    // ParaView ranges are in the data's own units: the stored numbers of a
    // raw or manifest volume, whose fixed-point values are read as [0, 1],
    // or a file's rescaled values.
    let (mut lo, mut hi) = tf.value_range();
    if let Some(volume) = volume.structured() {
        if volume.scaling() == volume.voxels().fixed_point() {
            (lo, hi) = (volume.scaling().apply(lo), volume.scaling().apply(hi));
        }
    }
    let tf = tf.with_value_range(lo, hi).map_err(|e| usage(&e))?;
    Ok((tf, false))
}

/// What `caveray view` changes of a placed volume while it runs: a move
/// after the placement, and the opacity of the transfer function.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Look {
    /// Applied in the rig's space after the volume is placed.
    pub moved: glam::Mat4,
    /// Every opacity times this (clamped to 1).
    pub opacity_gain: f32,
    /// Opacities below this fraction of the value range become 0.
    pub opacity_floor: f32,
}

impl Default for Look {
    fn default() -> Self {
        Self {
            moved: glam::Mat4::IDENTITY,
            opacity_gain: 1.0,
            opacity_floor: 0.0,
        }
    }
}

impl Look {
    /// `tf` with this look's opacity curve.
    fn reshape(&self, tf: TransferFunction) -> Result<TransferFunction, Failure> {
        if self.opacity_gain == 1.0 && self.opacity_floor <= 0.0 {
            return Ok(tf);
        }
        let table = tf.table();
        let last = (table.len() - 1).max(1) as f32;
        let opacities = table
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let t = i as f32 / last;
                if t < self.opacity_floor {
                    0.0
                } else {
                    (c.w * self.opacity_gain).clamp(0.0, 1.0)
                }
            })
            .collect();
        let colors = table.iter().map(|c| c.truncate().extend(1.0)).collect();
        TransferFunction::new(colors, opacities, tf.value_range(), tf.unit_distance())
            .map_err(|e| Failure::Usage(e.to_string()))
    }
}

impl Loaded {
    /// The volume with its axes as stored unless the command line turns
    /// it: for benchmark protocols, whose views are fixed, so that what is
    /// known about a data set's orientation cannot change a measurement.
    pub fn with_stored_axes(self) -> Self {
        Self {
            orientation: Orientation::UNKNOWN,
            ..self
        }
    }

    /// The volume's box in its own world: the file's, where it places its
    /// voxels, else its grid's.
    pub fn bounds(&self) -> (glam::Vec3, glam::Vec3) {
        match self.index_to_file {
            Some(affine) => transformed_box(affine, self.volume.bounds()),
            None => self.volume.bounds(),
        }
    }

    /// Where the volume goes: `default`, less what the command line says.
    pub fn placement(&self, default: ScenePlacement) -> Result<ScenePlacement, Failure> {
        self.placement.over(default, self.orientation)
    }

    /// The scene with the volume's bounding box centred where `default`
    /// or the command line says, its longest side that long, turned so its
    /// up and front axes point along `frame`'s up and toward its viewer.
    /// Opacities keep their look at any size: presets are tuned for a
    /// volume two units across.
    pub fn placed(
        &self,
        default: ScenePlacement,
        frame: &HeadFrame,
        world: Units,
    ) -> Result<Scene, Failure> {
        self.placed_in(default, frame, world, None)
    }

    /// `placed`, with the volume's value range given (`range`) rather than
    /// read from every voxel: a cluster rank knows it from the ranks'
    /// bricks.
    pub fn placed_in(
        &self,
        default: ScenePlacement,
        frame: &HeadFrame,
        world: Units,
        range: Option<(f32, f32)>,
    ) -> Result<Scene, Failure> {
        self.placed_as(default, frame, world, range, &Look::default())
    }

    /// The transfer function `spec` names (a preset or a ParaView map) in
    /// place of the one the volume was loaded with.
    pub fn set_tf(&mut self, spec: &str) -> Result<(), Failure> {
        (self.tf, self.stretch_tf) = transfer_function(spec, &self.volume)?;
        self.tf_name = spec.to_string();
        Ok(())
    }

    /// The preset's name or the ParaView file the transfer function came
    /// from.
    pub fn tf_name(&self) -> &str {
        &self.tf_name
    }

    /// `placed_in`, then moved and its opacities reshaped by `look`.
    pub fn placed_as(
        &self,
        default: ScenePlacement,
        frame: &HeadFrame,
        world: Units,
        range: Option<(f32, f32)>,
        look: &Look,
    ) -> Result<Scene, Failure> {
        let runtime = |e: &dyn std::fmt::Display| Failure::Runtime(e.to_string());
        let placement = self.placement(default)?;
        let (lo, hi) = self.bounds();
        let extent = f64::from((hi - lo).max_element());
        let size = placement.shown_size(extent, self.metres_per_unit, world) as f32;
        let centre = placement.centre.as_vec3();
        // A file's own placement is kept, scaled as a whole so that its
        // box in the file's world fits the rig's; the axes (RAS+ for a
        // NIfTI file) are then turned as any volume's.
        let (volume, fitted) = match (self.index_to_file, &self.volume) {
            (None, SpatialField::Structured(grid)) => (
                SpatialField::from(grid.clone().placed(centre, size)),
                glam::Mat4::IDENTITY,
            ),
            (affine, _) => {
                let affine = affine.unwrap_or(glam::Mat4::IDENTITY);
                let scale = size / (hi - lo).max_element().max(f32::MIN_POSITIVE);
                let fit = glam::Mat4::from_translation(centre)
                    * glam::Mat4::from_scale(glam::Vec3::splat(scale))
                    * glam::Mat4::from_translation(-0.5 * (lo + hi));
                (self.volume.clone(), fit * affine)
            }
        };
        let mut tf = self
            .tf
            .clone()
            .with_unit_distance(self.tf.unit_distance() * size / 2.0)
            .map_err(|e| runtime(&e))?;
        if self.stretch_tf {
            let (lo, hi) = range.unwrap_or_else(|| volume.value_range());
            if lo < hi {
                tf = tf.with_value_range(lo, hi).map_err(|e| runtime(&e))?;
            }
        }
        let tf = look.reshape(tf)?;
        let transform = look.moved * placement.transform(frame).as_mat4() * fitted;
        let mesh = match volume.structured() {
            Some(grid) => self.mesh.shape(grid, transform)?,
            None => None,
        };
        let scene = Scene::placed(vec![PlacedVolume {
            volume: std::sync::Arc::new(volume),
            transfer_function: tf.into(),
            transform,
            ids: ObjectIds::NONE,
        }])
        .map_err(|e| runtime(&e))?;
        match mesh {
            Some(shape) => scene.with_shapes(vec![shape]).map_err(|e| runtime(&e)),
            None => Ok(scene),
        }
    }
}

impl MeshArgs {
    /// The mesh `--mesh` asks for, of `volume` as placed by `transform`.
    pub fn shape(
        &self,
        volume: &StructuredVolume,
        transform: glam::Mat4,
    ) -> Result<Option<PlacedShape>, Failure> {
        let Some(fraction) = self.mesh else {
            return Ok(None);
        };
        let runtime = |e: &dyn std::fmt::Display| Failure::Runtime(e.to_string());
        let (lo, hi) = volume.value_range();
        let mesh = isosurface_mesh(
            volume,
            lo + fraction * (hi - lo),
            self.mesh_stride,
            MAX_MESH_TRIANGLES,
        )
        .map_err(|e| runtime(&e))?;
        let count = mesh.triangles.len();
        let input = ShapeInput {
            vertices: mesh.positions.len(),
            primitives: count,
            attributes: Default::default(),
            ids: None,
        };
        let made = Shape::triangles(
            mesh.positions,
            mesh.triangles,
            Kept::All(count),
            Some(mesh.normals.into()),
            input,
        )
        .map_err(|e| runtime(&e))?;
        let alpha = if self.mesh_opacity < 1.0 {
            AlphaMode::Blend
        } else {
            AlphaMode::Opaque
        };
        let material = SurfaceMaterial {
            color: ColorSource::Constant(self.mesh_color.as_vec3()),
            opacity: OpacitySource::Constant(self.mesh_opacity),
            alpha,
            pbr: None,
        };
        Ok(Some(PlacedShape::new(
            std::sync::Arc::new(made.shape),
            material,
            transform,
        )))
    }
}

/// A placement at `centre` of longest side `size`, the volume's axes the
/// world's: for commands that are not given a rig.
pub fn at(centre: glam::Vec3, size: f32) -> ScenePlacement {
    ScenePlacement {
        centre: centre.as_dvec3(),
        size: f64::from(size),
        life_size: None,
        up: None,
        front: None,
    }
}

/// `phantom[:N]`, `shells[:N]`, `marschner-lobb[:N]`, `box[:N]`,
/// `tets[:N]` or `amr[:N]`.
fn procedural(spec: &str) -> Result<Option<(String, SpatialField)>, Failure> {
    let (kind, size) = match spec.split_once(':') {
        Some((k, n)) => {
            let n: u32 = n
                .parse()
                .ok()
                .filter(|&n| (2..=1024).contains(&n))
                .ok_or_else(|| {
                    Failure::Usage(format!(
                        "volume size in '{spec}' must be a whole number in 2..=1024"
                    ))
                })?;
            (k, n)
        }
        None => (spec, PROCEDURAL_SIZE),
    };
    let make: fn(u32) -> StructuredVolume = match kind {
        "phantom" | "shepp-logan" => shepp_logan,
        "marschner-lobb" => marschner_lobb,
        "box" => solid_box,
        "shells" => concentric_shells,
        "tets" => {
            let mesh = tetrahedra(size).map_err(|e| Failure::Usage(format!("{spec}: {e}")))?;
            return Ok(Some((format!("{kind}:{size}"), mesh.into())));
        }
        "amr" => {
            // Whole blocks on every level: the finest cells a multiple
            // of 16 across.
            let n = (size / 16).max(1) * 16;
            let amr =
                refined(n, 3, smooth_waves).map_err(|e| Failure::Usage(format!("{spec}: {e}")))?;
            return Ok(Some((format!("{kind}:{n}"), amr.into())));
        }
        _ => return Ok(None),
    };
    Ok(Some((format!("{kind}:{size}"), make(size).into())))
}

/// Whether `path` is an HDF5 file (FLASH's), by its first bytes.
/// Whether `path` is a NanoVDB file (or raw grid buffers).
pub fn is_nvdb_file(path: &Path) -> bool {
    use std::io::Read;
    let mut head = [0u8; 8];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut head))
        .is_ok()
        && anari_library_caveray::data::is_nvdb(&head)
}

pub fn is_hdf5_file(path: &Path) -> bool {
    use std::io::Read;
    let mut head = [0u8; 8];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut head))
        .is_ok()
        && is_hdf5(&head)
}

/// A FLASH file's AMR field, `variable` or its first.
#[cfg(feature = "hdf5")]
pub fn load_flash_file(
    spec: &str,
    variable: Option<&str>,
) -> Result<anari_library_caveray::scene::AmrVolume, Failure> {
    anari_library_caveray::data::load_flash(Path::new(spec), variable)
        .map(|f| f.amr)
        .map_err(|e| Failure::Usage(e.to_string()))
}

#[cfg(not(feature = "hdf5"))]
pub fn load_flash_file(
    spec: &str,
    _: Option<&str>,
) -> Result<anari_library_caveray::scene::AmrVolume, Failure> {
    Err(Failure::Usage(format!(
        "{spec} is an HDF5 file; this caveray was built without HDF5 (cargo build --features hdf5, with Debian's libhdf5-dev) and cannot read FLASH files"
    )))
}

/// Whether `path` is a VTK unstructured grid, by its first bytes.
pub fn is_mesh_file(path: &Path) -> bool {
    use std::io::Read;
    let mut head = [0u8; 4096];
    let Ok(mut file) = std::fs::File::open(path) else {
        return false;
    };
    let n = file.read(&mut head).unwrap_or(0);
    path.is_file() && is_vtk_mesh(&head[..n])
}

fn file_stem(path: &str) -> String {
    Path::new(path)
        .file_stem()
        .map_or_else(|| path.to_string(), |s| s.to_string_lossy().into_owned())
}

/// The frame of a viewer in front of a display panel: looking into it,
/// up its right edge.
pub fn panel_frame(panel: &anari_library_caveray::geometry::Screen) -> HeadFrame {
    HeadFrame::new(-panel.normal(), panel.y_axis()).unwrap_or(protocol_frame())
}

/// The unit of the benchmark protocols' views (radii of a few units around
/// a volume), which `--volume-units` shows a volume's own size in.
pub const PROTOCOL_UNITS: Units = Units::Metres;

/// The benchmark protocols' first view: looking down -z, y up.
pub fn protocol_frame() -> HeadFrame {
    HeadFrame {
        forward: DVec3::NEG_Z,
        up: DVec3::Y,
        right: DVec3::X,
    }
}

/// What to do about a `--volume` that is neither procedural nor a file
/// in a known format: a missing file, no manifest, or a name the manifest
/// lacks.
fn unknown_volume(spec: &str, e: &DataError) -> Failure {
    let kinds = "phantom[:N], shells[:N], marschner-lobb[:N], box[:N]";
    let path = Path::new(spec);
    Failure::Usage(match e {
        _ if path.is_dir() => format!(
            "{spec} is a folder without DICOM slices, not a volume (--volume takes {kinds}, \
             a name from volumes.toml or a raw file)"
        ),
        _ if path.exists() => format!("{spec} is not a regular file"),
        // Names in a manifest are words, never paths.
        _ if spec.contains(['/', std::path::MAIN_SEPARATOR]) => format!("{spec}: no such file"),
        DataError::NoManifest { tried } => format!(
            "no volume manifest found to look '{spec}' up in (tried {tried}): pass \
             --manifest FILE or set CAVERAY_DATA=DIR, the folder holding volumes.toml \
             (docs/data.md says where the data sets come from)"
        ),
        DataError::UnknownVolume { .. } => {
            format!("{e}, nor is there such a file; --volume also takes {kinds} or a raw file")
        }
        other => other.to_string(),
    })
}

/// Why a gzipped raw file is not loaded, and what to do instead.
fn gzipped(spec: &str, dims_given: bool) -> String {
    let dims = if dims_given {
        " (--dims, --dtype and --spacing describe raw files only)"
    } else {
        ""
    };
    format!(
        "{spec} is gzip-compressed{dims}; caveray reads raw volumes uncompressed: \
         decompress it (gunzip -k {spec}) and load the file it holds"
    )
}
