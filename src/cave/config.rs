//! The TOML rig format: parsing, validation and errors that name the file,
//! the line and the field.

use std::collections::HashSet;
use std::ops::Range;
use std::path::Path;

use glam::{DVec3, UVec2};
use serde::de::DeserializeOwned;
use serde::Deserialize;
use thiserror::Error;
use toml::Spanned;

use super::head::{HeadFrame, HeadPose, PathKey};
use super::placement::ScenePlacement;
use super::rig::{Eye, Rig, Viewer, Wall};
use super::source_map::locate;
use crate::data::toml_syntax::syntax_error;
use crate::geometry::{GeometryError, Rounded, Screen, Units, VolumeAxis};

/// Clip planes for rigs that do not set them, in metres.
const DEFAULT_NEAR_M: f64 = 0.01;
const DEFAULT_FAR_M: f64 = 100.0;
const DEFAULT_IPD_M: f64 = 0.063;

#[derive(Debug, Error)]
pub enum ConfigError {
    #[error("{file}: cannot read {what}: {source}")]
    Io {
        file: String,
        /// "rig file" or "head path".
        what: &'static str,
        source: std::io::Error,
    },
    /// Text that is not TOML: it names the place, not a field.
    #[error("{file}:{line}:{column}: {message}")]
    Syntax {
        file: String,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("{file}:{line}:{column}: {field}: {message}")]
    Invalid {
        file: String,
        line: usize,
        column: usize,
        field: String,
        message: String,
    },
}

impl ConfigError {
    /// The dotted path of the offending field, e.g. `walls[1].ul`; none
    /// for a syntax error.
    pub fn field(&self) -> Option<&str> {
        match self {
            ConfigError::Invalid { field, .. } => Some(field),
            ConfigError::Syntax { .. } | ConfigError::Io { .. } => None,
        }
    }
    pub fn line(&self) -> Option<usize> {
        match self {
            ConfigError::Invalid { line, .. } | ConfigError::Syntax { line, .. } => Some(*line),
            ConfigError::Io { .. } => None,
        }
    }
    pub fn column(&self) -> Option<usize> {
        match self {
            ConfigError::Invalid { column, .. } | ConfigError::Syntax { column, .. } => {
                Some(*column)
            }
            ConfigError::Io { .. } => None,
        }
    }
}

/// Read as a list, so that a wrong number of components is an error
/// naming the field rather than something serde may pass over.
pub(super) type Vec3 = Spanned<Vec<f64>>;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRig {
    name: Option<String>,
    units: Spanned<Units>,
    near: Option<Spanned<f64>>,
    far: Option<Spanned<f64>>,
    viewer: RawViewer,
    scene: Option<RawScene>,
    walls: Spanned<Vec<Spanned<RawWall>>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    centre: Option<Vec3>,
    size: Option<Spanned<f64>>,
    units: Option<Spanned<Units>>,
    volume_up: Option<Spanned<String>>,
    volume_front: Option<Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawViewer {
    ipd: Option<Spanned<f64>>,
    head: Vec3,
    head_ypr: Option<Vec3>,
    forward: Option<Vec3>,
    up: Option<Vec3>,
    eye_offset: Option<Vec3>,
    tracked_space: Option<Spanned<RawBox>>,
    #[serde(default)]
    path: Vec<RawPathKey>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBox {
    min: Vec3,
    max: Vec3,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPathKey {
    t: Spanned<f64>,
    head: Vec3,
    ypr: Option<Vec3>,
}

/// A head path file: a recorded or scripted walk through a rig.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawHeadPath {
    units: Spanned<Units>,
    #[serde(default)]
    pose: Vec<RawPathKey>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawWall {
    name: Spanned<String>,
    ll: Vec3,
    lr: Vec3,
    ur: Vec3,
    ul: Option<Vec3>,
    resolution: Spanned<Vec<u32>>,
    eyes: Option<Spanned<Vec<Eye>>>,
}

/// A TOML file's text and its name for messages.
pub(super) fn read(path: &Path, what: &'static str) -> Result<(String, String), ConfigError> {
    let file = path.display().to_string();
    match crate::data::files::read_text(path, crate::data::files::TEXT_LIMIT) {
        Ok(text) => Ok((text, file)),
        Err(source) => Err(ConfigError::Io { file, what, source }),
    }
}

/// The one key that tells a display's file from a rig's.
#[derive(Deserialize)]
struct Probe {
    views: Option<Spanned<toml::Value>>,
}

pub(super) struct Ctx<'a> {
    pub text: &'a str,
    pub file: &'a str,
}

impl Ctx<'_> {
    /// The text as `T`: text that is not TOML is reported where its
    /// cause is, without a field; TOML that is not a `T`, with the field.
    pub(super) fn parse<T: DeserializeOwned>(&self) -> Result<T, ConfigError> {
        toml::from_str(self.text).map_err(|e| match syntax_error(self.text) {
            Some(s) => ConfigError::Syntax {
                file: self.file.to_string(),
                line: s.line,
                column: s.column,
                message: s.message,
            },
            None => self.error(e.span().unwrap_or(0..0), None, e.message().to_string()),
        })
    }

    /// An error at `span`; `field` overrides the path found from the text
    /// (which at a table header only names the table).
    pub(super) fn error(
        &self,
        span: Range<usize>,
        field: Option<String>,
        message: String,
    ) -> ConfigError {
        let loc = locate(self.text, span.start);
        let mut path = loc.path;
        if field.is_none() {
            if let Some(missing) = backticked(&message, "missing field `") {
                path = join(&path, missing);
            }
        }
        ConfigError::Invalid {
            file: self.file.to_string(),
            line: loc.line,
            column: loc.column,
            field: field.unwrap_or(path),
            message,
        }
    }

    pub(super) fn at<T>(&self, value: &Spanned<T>, field: String, message: String) -> ConfigError {
        self.error(value.span(), Some(field), message)
    }

    fn volume_axis(
        &self,
        v: &Option<Spanned<String>>,
        field: &str,
    ) -> Result<Option<VolumeAxis>, ConfigError> {
        v.as_ref()
            .map(|s| s.get_ref().parse().map_err(|e| self.at(s, field.into(), e)))
            .transpose()
    }

    pub(super) fn vec3(&self, v: &Vec3, field: impl Fn() -> String) -> Result<DVec3, ConfigError> {
        let [x, y, z] = v.get_ref()[..] else {
            let n = v.get_ref().len();
            return Err(self.at(v, field(), format!("expected 3 numbers, got {n}")));
        };
        let p = DVec3::new(x, y, z);
        if !p.is_finite() {
            return Err(self.at(v, field(), "coordinates must be finite numbers".into()));
        }
        match p.to_array().into_iter().find(|&x| !fits_f32(x)) {
            Some(x) => Err(self.at(v, field(), beyond_f32(x))),
            None => Ok(p),
        }
    }

    pub(super) fn positive(
        &self,
        v: &Spanned<f64>,
        field: &str,
        allow_zero: bool,
    ) -> Result<f64, ConfigError> {
        let x = *v.get_ref();
        if x.is_finite() && !fits_f32(x) {
            Err(self.at(v, field.into(), beyond_f32(x)))
        } else if x.is_finite() && (x > 0.0 || (allow_zero && x == 0.0)) {
            Ok(x)
        } else {
            let want = if allow_zero { ">= 0" } else { "> 0" };
            Err(self.at(
                v,
                field.into(),
                format!("must be a finite number {want}, got {}", Rounded(x)),
            ))
        }
    }

    fn validate(&self, raw: RawRig) -> Result<Rig, ConfigError> {
        let units = *raw.units.get_ref();
        let per_m = 1.0 / units.metres_per_unit();
        let near = match &raw.near {
            Some(v) => self.positive(v, "near", false)?,
            None => DEFAULT_NEAR_M * per_m,
        };
        let far = match &raw.far {
            Some(v) => self.positive(v, "far", false)?,
            None => DEFAULT_FAR_M * per_m,
        };
        if far <= near {
            let span = raw
                .far
                .as_ref()
                .or(raw.near.as_ref())
                .map_or(0..0, |v| v.span());
            return Err(self.error(
                span,
                Some("far".into()),
                format!(
                    "far ({}) must be greater than near ({})",
                    Rounded(far),
                    Rounded(near)
                ),
            ));
        }
        let viewer = self.viewer(&raw.viewer, per_m)?;
        if raw.walls.get_ref().is_empty() {
            return Err(self.at(
                &raw.walls,
                "walls".into(),
                "a rig needs at least one wall".into(),
            ));
        }
        let mut names = HashSet::new();
        let mut walls = Vec::new();
        for (i, w) in raw.walls.get_ref().iter().enumerate() {
            let wall = self.wall(w.get_ref(), i)?;
            if !names.insert(wall.name.to_ascii_lowercase()) {
                let name = &w.get_ref().name;
                return Err(self.at(
                    name,
                    format!("walls[{i}].name"),
                    format!("duplicate wall name \"{}\"", wall.name),
                ));
            }
            walls.push(wall);
        }
        let scene = ScenePlacement::around(walls.iter().flat_map(|w| w.screen.corners()));
        let scene = match &raw.scene {
            None => scene,
            Some(s) => {
                let up = self.volume_axis(&s.volume_up, "scene.volume_up")?;
                let front = self.volume_axis(&s.volume_front, "scene.volume_front")?;
                if let (Some(at), Err(e)) = (&s.volume_front, ScenePlacement::check_axes(up, front))
                {
                    return Err(self.at(at, "scene.volume_front".into(), e));
                }
                ScenePlacement {
                    centre: match &s.centre {
                        Some(c) => self.vec3(c, || "scene.centre".into())?,
                        None => scene.centre,
                    },
                    size: match &s.size {
                        Some(v) => self.positive(v, "scene.size", false)?,
                        None => scene.size,
                    },
                    life_size: match (&s.units, &s.size) {
                        (Some(u), Some(_)) => {
                            return Err(self.at(
                                u,
                                "scene.units".into(),
                                "shows the volume at its own size, which scene.size sets \
                                 otherwise: give one of them"
                                    .into(),
                            ))
                        }
                        (u, _) => u.as_ref().map(|u| *u.get_ref()),
                    },
                    up,
                    front,
                }
            }
        };
        let rig = Rig {
            name: raw.name.clone().unwrap_or_else(|| self.file.to_string()),
            units,
            near,
            far,
            viewer,
            scene,
            walls,
        };
        self.eyes_fit_f32(&raw.viewer, &rig)?;
        Ok(rig)
    }

    /// Each field fits f32 on its own; an eye is a sum of them (head,
    /// offset, half the ipd), which may not.
    fn eyes_fit_f32(&self, raw: &RawViewer, rig: &Rig) -> Result<(), ConfigError> {
        let viewer = &rig.viewer;
        let poses = std::iter::once(&viewer.head).chain(viewer.path.iter().map(|k| &k.pose));
        for pose in poses {
            for eye in Eye::ALL {
                let at = rig.eye_position(pose, eye);
                if let Some(x) = at.to_array().into_iter().find(|&x| !fits_f32(x)) {
                    let culprit = raw.eye_offset.as_ref().unwrap_or(&raw.head);
                    return Err(self.at(
                        culprit,
                        "viewer".into(),
                        format!(
                            "the {eye} eye lies at [{}, {}, {}]: {}",
                            Rounded(at.x),
                            Rounded(at.y),
                            Rounded(at.z),
                            beyond_f32(x)
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    fn viewer(&self, raw: &RawViewer, per_m: f64) -> Result<Viewer, ConfigError> {
        let ipd = match &raw.ipd {
            Some(v) => self.positive(v, "viewer.ipd", true)?,
            None => DEFAULT_IPD_M * per_m,
        };
        let forward = match &raw.forward {
            Some(v) => self.vec3(v, || "viewer.forward".into())?,
            None => DVec3::NEG_Z,
        };
        let up = match &raw.up {
            Some(v) => self.vec3(v, || "viewer.up".into())?,
            None => DVec3::Y,
        };
        let frame = HeadFrame::new(forward, up).ok_or_else(|| {
            let span = raw
                .up
                .as_ref()
                .or(raw.forward.as_ref())
                .map_or(0..0, |v| v.span());
            self.error(
                span,
                Some("viewer.up".into()),
                "forward and up must be non-zero and not parallel".into(),
            )
        })?;
        let head = self.pose(&raw.head, raw.head_ypr.as_ref(), "viewer", &frame, 1.0)?;
        let eye_offset = match &raw.eye_offset {
            Some(v) => self.vec3(v, || "viewer.eye_offset".into())?,
            None => DVec3::ZERO,
        };
        let tracked_space = match &raw.tracked_space {
            Some(b) => {
                let min = self.vec3(&b.get_ref().min, || "viewer.tracked_space.min".into())?;
                let max = self.vec3(&b.get_ref().max, || "viewer.tracked_space.max".into())?;
                if !min.cmplt(max).all() {
                    return Err(self.at(
                        b,
                        "viewer.tracked_space".into(),
                        "min must be below max on every axis".into(),
                    ));
                }
                Some((min, max))
            }
            None => None,
        };
        let path = self.path(&raw.path, "viewer.path", &frame, 1.0)?;
        Ok(Viewer {
            ipd,
            frame,
            eye_offset,
            head,
            tracked_space,
            path,
        })
    }

    /// A head position (times `scale`, to the rig's units) and yaw,
    /// pitch, roll in degrees.
    fn pose(
        &self,
        head: &Vec3,
        ypr: Option<&Vec3>,
        field: &str,
        frame: &HeadFrame,
        scale: f64,
    ) -> Result<HeadPose, ConfigError> {
        let position = self.vec3(head, || format!("{field}.head"))? * scale;
        let ypr = match ypr {
            Some(v) => self.vec3(v, || format!("{field}.ypr"))?,
            None => DVec3::ZERO,
        };
        Ok(HeadPose {
            position,
            orientation: frame.orientation(ypr),
        })
    }

    /// Timed poses, times finite and increasing.
    fn path(
        &self,
        keys: &[RawPathKey],
        field: &str,
        frame: &HeadFrame,
        scale: f64,
    ) -> Result<Vec<PathKey>, ConfigError> {
        let mut path: Vec<PathKey> = Vec::with_capacity(keys.len());
        for (i, k) in keys.iter().enumerate() {
            let field = format!("{field}[{i}]");
            let time = *k.t.get_ref();
            if !time.is_finite() || path.last().is_some_and(|p| time <= p.time) {
                return Err(self.at(
                    &k.t,
                    format!("{field}.t"),
                    format!("times must be finite and increasing, got {}", Rounded(time)),
                ));
            }
            path.push(PathKey {
                time,
                pose: self.pose(&k.head, k.ypr.as_ref(), &field, frame, scale)?,
            });
        }
        Ok(path)
    }

    fn wall(&self, raw: &RawWall, i: usize) -> Result<Wall, ConfigError> {
        let field = |f: &str| format!("walls[{i}].{f}");
        let name = raw.name.get_ref().trim().to_string();
        if let Err(why) = check_wall_name(&name) {
            return Err(self.at(&raw.name, field("name"), why));
        }
        let ll = self.vec3(&raw.ll, || field("ll"))?;
        let lr = self.vec3(&raw.lr, || field("lr"))?;
        let ur = self.vec3(&raw.ur, || field("ur"))?;
        let screen = match &raw.ul {
            Some(ul) => Screen::with_upper_left(ll, lr, ur, self.vec3(ul, || field("ul"))?),
            None => Screen::new(ll, lr, ur),
        };
        let screen = screen.map_err(|e| {
            // Point at the corner that makes the wall wrong.
            let (culprit, key) = match &e {
                GeometryError::NotPlanar { .. } => (raw.ul.as_ref().unwrap_or(&raw.ur), "ul"),
                GeometryError::ZeroAreaWall { width, .. } if *width == 0.0 => (&raw.lr, "lr"),
                _ => (&raw.ur, "ur"),
            };
            self.at(culprit, field(key), format!("wall \"{name}\": {e}"))
        })?;
        let [w, h] = raw.resolution.get_ref()[..] else {
            let n = raw.resolution.get_ref().len();
            return Err(self.at(
                &raw.resolution,
                field("resolution"),
                format!("wall \"{name}\": expected 2 numbers (width, height), got {n}"),
            ));
        };
        if w == 0 || h == 0 {
            return Err(self.at(
                &raw.resolution,
                field("resolution"),
                format!("wall \"{name}\": resolution must be at least 1 x 1, got {w} x {h}"),
            ));
        }
        let eyes = match &raw.eyes {
            Some(e) => {
                let list = e.get_ref();
                let unique: HashSet<_> = list.iter().collect();
                if list.is_empty() || unique.len() != list.len() {
                    return Err(self.at(
                        e,
                        field("eyes"),
                        format!(
                            "wall \"{name}\": eyes must list left, right or mono at most once each"
                        ),
                    ));
                }
                list.clone()
            }
            None => vec![Eye::Left, Eye::Right],
        };
        Ok(Wall {
            name,
            screen,
            resolution: UVec2::new(w, h),
            eyes,
        })
    }
}

/// Whether `x` survives the renderers' single precision: rays, corners
/// and clip distances are f32 there, and a value beyond it becomes
/// infinite, so that every view would fail when it renders.
fn fits_f32(x: f64) -> bool {
    x.abs() <= f64::from(f32::MAX)
}

fn beyond_f32(x: f64) -> String {
    format!(
        "{} is beyond single precision (at most {} in size), which caveray renders in",
        Rounded(x),
        Rounded::from(f32::MAX)
    )
}

/// The longest wall name: it becomes part of file names.
pub const MAX_WALL_NAME: usize = 64;

/// Wall names become file names (`<wall>_<eye>.png` beside the contact
/// sheets `cave_<eye>.png`), so they are kept to characters every file
/// system takes, cannot climb out of the output folder, and cannot be the
/// contact sheets' name.
fn check_wall_name(name: &str) -> Result<(), String> {
    let safe = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '-';
    if name.is_empty() {
        Err("wall name must not be empty".into())
    } else if name.len() > MAX_WALL_NAME || !name.chars().all(safe) {
        Err(format!(
            "wall name \"{}\" must be 1 to {MAX_WALL_NAME} letters, digits, '_' or '-' (it names the wall's image files)",
            name.escape_debug()
        ))
    } else if name.eq_ignore_ascii_case("cave") {
        Err("wall name \"cave\" is taken by the contact sheets (cave_<eye>.png)".into())
    } else {
        Ok(())
    }
}

fn backticked<'m>(message: &'m str, prefix: &str) -> Option<&'m str> {
    let rest = message.split_once(prefix)?.1;
    rest.split('`').next()
}

fn join(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    }
}

/// Rigs and head paths are read from files here alone, so the rig types
/// know nothing of TOML.
impl Rig {
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let (text, file) = read(path, "rig file")?;
        Self::from_toml(&text, &file)
    }

    /// Parses rig TOML; `file` names the source in error messages.
    pub fn from_toml(text: &str, file: &str) -> Result<Self, ConfigError> {
        let ctx = Ctx { text, file };
        // A multi-view display's file is not a rig: say so rather than
        // reporting its fields as unknown.
        if let Ok(Probe { views: Some(views) }) = toml::from_str::<Probe>(text) {
            return Err(ctx.at(
                &views,
                "views".into(),
                format!(
                    "this is a multi-view display (views = {}), not a rig: load it as a display",
                    views.get_ref()
                ),
            ));
        }
        let raw: RawRig = ctx.parse()?;
        ctx.validate(raw)
    }

    /// A head path file's poses (`[[pose]]` with `t`, `head`, `ypr`, in
    /// the file's `units`), in this rig's units and head frame.
    pub fn load_head_path(&self, path: &Path) -> Result<Vec<PathKey>, ConfigError> {
        let (text, file) = read(path, "head path")?;
        self.head_path_from_toml(&text, &file)
    }

    /// A head path from TOML text; `file` names it in error messages.
    pub fn head_path_from_toml(&self, text: &str, file: &str) -> Result<Vec<PathKey>, ConfigError> {
        let ctx = Ctx { text, file };
        let raw: RawHeadPath = ctx.parse()?;
        if raw.pose.is_empty() {
            return Err(ctx.error(
                0..0,
                Some("pose".into()),
                "a head path needs at least one [[pose]] (t, head, ypr)".into(),
            ));
        }
        let scale = raw.units.get_ref().metres_per_unit() / self.units.metres_per_unit();
        ctx.path(&raw.pose, "pose", &self.viewer.frame, scale)
    }
}
