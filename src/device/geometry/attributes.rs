//! What every surface geometry reads the same way: vertex positions,
//! index arrays, and the attributes a material may color by, per vertex
//! (`vertex.color`, `vertex.attribute0..3`) or per primitive
//! (`primitive.*`, which win where both are set), with `primitive.id`.

use glam::{Vec3, Vec4};

use crate::device::array::Array;
use crate::device::elements::{colors, COLOR_ELEMENTS, COLOR_TYPES};
use crate::device::table::Read;
use crate::device::types::{words, DataType as T};
use crate::scene::{Attribute, ShapeInput, ATTRIBUTE_NAMES};

/// Element types an attribute array may hold (every color type); missing
/// components read as ANARI's (x, 0, 0, 1).
pub const ATTRIBUTE_ELEMENTS: &[T] = COLOR_ELEMENTS;

/// Triangles' and quads' normals.
pub const VERTEX_NORMAL: crate::device::table::ParamInfo = crate::device::table::p(
    "vertex.normal",
    &[T::ARRAY1D],
    false,
    crate::device::table::DefaultValue::None,
    "FLOAT32_VEC3 per vertex, interpolated for shading (default: each face's own)",
)
.elements(&[T::FLOAT32_VEC3]);

/// A surface geometry's parameter table: `vertex.position`, the entries
/// given, then the attributes and `primitive.id`.
macro_rules! shape_params {
    ($($entry:expr),* $(,)?) => {
        $crate::device::geometry::attributes::shape_params!(@each [$($entry),*]
            "vertex.color", "vertex.attribute0", "vertex.attribute1",
            "vertex.attribute2", "vertex.attribute3",
            "primitive.color", "primitive.attribute0", "primitive.attribute1",
            "primitive.attribute2", "primitive.attribute3")
    };
    (@each [$($entry:expr),*] $($name:literal),*) => {
        [
        $crate::device::table::p(
            "vertex.position",
            &[$crate::device::types::DataType::ARRAY1D],
            true,
            $crate::device::table::DefaultValue::None,
            "FLOAT32_VEC3 per vertex",
        )
        .elements(&[$crate::device::types::DataType::FLOAT32_VEC3]),
        $($entry,)*
        $(
            $crate::device::table::p(
                $name,
                &[$crate::device::types::DataType::ARRAY1D],
                false,
                $crate::device::table::DefaultValue::None,
                "per vertex (interpolated) or per primitive: what a material's color may name (FLOAT32, UFIXED8, UFIXED16 or UFIXED32 with 1 to 4 components, or UFIXED8_*_SRGB)",
            )
            .elements($crate::device::geometry::attributes::ATTRIBUTE_ELEMENTS),
        )*
        $crate::device::table::p(
            "primitive.id",
            &[$crate::device::types::DataType::ARRAY1D],
            false,
            $crate::device::table::DefaultValue::None,
            "UINT32 per primitive: the primitiveId channel's value (default: the primitive's index)",
        )
        .elements(&[$crate::device::types::DataType::UINT32])]
    };
}
pub(crate) use shape_params;

/// An attribute array's elements as Vec4s.
pub fn vec4s(name: &str, a: &Array) -> Result<Vec<Vec4>, String> {
    colors(a).ok_or_else(|| {
        format!(
            "'{name}' array holds {}; attributes are {COLOR_TYPES}",
            a.element()
        )
    })
}

/// The FLOAT32_VEC3 array `name`, if set.
pub fn vec3s(r: &Read<'_>, name: &str) -> Result<Option<Vec<Vec3>>, String> {
    r.array_of(name, T::FLOAT32_VEC3, |a| {
        Ok(a.f32s().chunks_exact(3).map(Vec3::from_slice).collect())
    })
}

/// The FLOAT32 array `name`, if set.
pub fn f32s(r: &Read<'_>, name: &str) -> Result<Option<Vec<f32>>, String> {
    r.array_of(name, T::FLOAT32, |a| Ok(a.f32s()))
}

/// The array `name` of UINT32 tuples of `element`, if set.
pub fn indices(r: &Read<'_>, name: &str, element: T) -> Result<Option<Vec<u32>>, String> {
    r.array_of(name, element, |a| {
        Ok(words::<4>(a.bytes()).map(u32::from_ne_bytes).collect())
    })
}

/// `name` (of `element`, three UINT32s) as vertex triples, read in one
/// pass: a million triangles' indices are not held twice.
pub fn triples(r: &Read<'_>, name: &str, element: T) -> Result<Option<Vec<[u32; 3]>>, String> {
    r.array_of(name, element, |a| {
        let mut out = Vec::new();
        out.try_reserve_exact(a.bytes().len() / 12)
            .map_err(|_| format!("'{name}': cannot hold {} bytes of indices", a.bytes().len()))?;
        out.extend(a.bytes().chunks_exact(12).map(|c| {
            let word = |k: usize| u32::from_ne_bytes([c[k], c[k + 1], c[k + 2], c[k + 3]]);
            [word(0), word(4), word(8)]
        }));
        Ok(out)
    })
}

/// `primitive.index` as vertex pairs, else vertices 2i and 2i + 1.
pub fn pairs(r: &Read<'_>, vertices: usize) -> Result<Vec<[u32; 2]>, String> {
    let flat = match indices(r, "primitive.index", T::UINT32_VEC2)? {
        Some(i) => i,
        None => (0..(vertices / 2 * 2) as u32).collect(),
    };
    Ok(flat.chunks_exact(2).map(|e| [e[0], e[1]]).collect())
}

/// The cap modes cones and cylinders take, by name.
pub const CAPS: [&str; 4] = ["none", "first", "second", "both"];

/// `caps`: which ends are closed. An unknown name falls back to the
/// default (the spec's rule for enumerations), with a warning.
pub fn caps(r: &Read<'_>, warn: &mut dyn FnMut(String)) -> [bool; 2] {
    match r.string("caps").unwrap_or("none") {
        "none" => [false, false],
        "first" => [true, false],
        "second" => [false, true],
        "both" => [true, true],
        other => {
            warn(format!(
                "caps '{other}' is not one of {}; the ends are open",
                CAPS.join(", ")
            ));
            [false, false]
        }
    }
}

/// Cones' and cylinders' caps per vertex.
pub const VERTEX_CAP: crate::device::table::ParamInfo = crate::device::table::p(
    "vertex.cap",
    &[T::ARRAY1D],
    false,
    crate::device::table::DefaultValue::None,
    "UINT8 per vertex: a disc closes the end at that vertex where it is not 0 (default: 'caps')",
)
.elements(&[T::UINT8]);

/// Which ends of each of `ends` are closed: by `vertex.cap` where it is
/// given, else by `caps` for every one.
pub fn end_caps(
    r: &Read<'_>,
    vertices: usize,
    ends: &[[u32; 2]],
    warn: &mut dyn FnMut(String),
) -> Result<Vec<[bool; 2]>, String> {
    let global = caps(r, warn);
    let Some(per_vertex) = r.array_of("vertex.cap", T::UINT8, |a| Ok(a.bytes().to_vec()))? else {
        return Ok(vec![global; ends.len()]);
    };
    if per_vertex.len() < vertices {
        return Err(format!(
            "vertex.cap has {} values for {vertices} vertices",
            per_vertex.len()
        ));
    }
    // An end past the vertices is the shape's to report.
    let at = |v: u32| per_vertex.get(v as usize).is_some_and(|&c| c != 0);
    Ok(ends.iter().map(|e| [at(e[0]), at(e[1])]).collect())
}

/// `vertex.radius`, one per vertex, else `radius` for every vertex.
pub fn vertex_radii(r: &Read<'_>, vertices: usize) -> Result<Vec<f32>, String> {
    match f32s(r, "vertex.radius")? {
        Some(radii) if radii.len() < vertices => Err(format!(
            "vertex.radius has {} values for {vertices} vertices",
            radii.len()
        )),
        Some(radii) => Ok(radii),
        None => Ok(vec![r.f32("radius")?; vertices]),
    }
}

/// `vertex.position`: required.
pub fn positions(r: &Read<'_>) -> Result<Vec<Vec3>, String> {
    vec3s(r, "vertex.position")?
        .ok_or_else(|| "parameter 'vertex.position' (ARRAY1D of FLOAT32_VEC3) is required".into())
}

/// The attributes and ids of a geometry of `vertices` vertices and
/// `primitives` host primitives, ready for the shape's checks.
pub fn input(r: &Read<'_>, vertices: usize, primitives: usize) -> Result<ShapeInput, String> {
    let mut attributes: [Option<Attribute>; 5] = Default::default();
    for (slot, name) in ATTRIBUTE_NAMES.iter().enumerate() {
        let vertex = format!("vertex.{name}");
        let primitive = format!("primitive.{name}");
        attributes[slot] = match r.array(&primitive, |a| vec4s(&primitive, a))? {
            Some(v) => Some(Attribute::PerPrimitive(v)),
            None => r
                .array(&vertex, |a| vec4s(&vertex, a))?
                .map(Attribute::PerVertex),
        };
    }
    Ok(ShapeInput {
        vertices,
        primitives,
        attributes,
        ids: indices(r, "primitive.id", T::UINT32)?,
    })
}
