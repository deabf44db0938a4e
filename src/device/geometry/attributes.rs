//! What every surface geometry reads the same way: vertex positions,
//! index arrays, and the attributes a material may color by, per vertex
//! (`vertex.color`, `vertex.attribute0..3`) or per primitive
//! (`primitive.*`, which win where both are set), with `primitive.id`.

use glam::{Vec3, Vec4};

use crate::device::array::Array;
use crate::device::elements::{colors, COLOR_ELEMENTS, COLOR_TYPES};
use crate::device::object::ObjectRef;
use crate::device::table::Read;
use crate::device::types::{words, DataType as T};
use crate::scene::{Attribute, Buf, ShapeInput, ATTRIBUTE_NAMES};

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

/// The arrays a shape reads from the host's memory in place: its
/// committed state holds them, so that a host releasing one while the
/// shape still uses it has it copied first.
pub type Holds = Vec<ObjectRef>;

/// The elements of array `a` as numbers `N` of its size: where the host
/// shares the array, its memory read where it lies (and the array added
/// to `holds`), else a copy.
fn numbers<N: bytemuck::Pod>(
    r: &Read<'_>,
    name: &str,
    a: &Array,
    holds: &mut Holds,
) -> Result<Buf<N>, String> {
    let size = std::mem::size_of::<N>();
    let n = a.bytes().len() / size;
    if let Some(lent) = a.lent() {
        if let Some(b) = Buf::lent(std::sync::Arc::clone(lent), n) {
            holds.extend(r.object(name).cloned());
            return Ok(b);
        }
        r.cost(format!(
            "'{name}' ({} bytes) is copied: its memory is not aligned to {} bytes",
            a.bytes().len(),
            std::mem::align_of::<N>()
        ));
    }
    let mut out = Vec::new();
    out.try_reserve_exact(n)
        .map_err(|_| format!("'{name}': cannot hold {} bytes", a.bytes().len()))?;
    out.extend(
        a.bytes()
            .chunks_exact(size)
            .map(bytemuck::pod_read_unaligned::<N>),
    );
    Ok(Buf::from(out))
}

/// An attribute array's elements as Vec4s.
pub fn vec4s(name: &str, a: &Array) -> Result<Vec<Vec4>, String> {
    colors(a).ok_or_else(|| {
        format!(
            "'{name}' array holds {}; attributes are {COLOR_TYPES}",
            a.element()
        )
    })
}

/// A shape's attribute array: FLOAT32_VEC4 read in place where the host
/// shares it, other types converted.
fn attribute(
    r: &Read<'_>,
    name: &str,
    a: &Array,
    holds: &mut Holds,
) -> Result<Buf<[f32; 4]>, String> {
    if a.element() == T::FLOAT32_VEC4 {
        return numbers(r, name, a, holds);
    }
    if a.lent().is_some() {
        r.cost(format!(
            "'{name}' ({}) is converted: attributes are read in place as FLOAT32_VEC4",
            a.element()
        ));
    }
    let values = vec4s(name, a)?;
    Ok(values.iter().map(Vec4::to_array).collect::<Vec<_>>().into())
}

/// The array `name` of `element`s as numbers `N` of its size, if set:
/// in place where the host shares it (see [`numbers`]).
pub fn shared<N: bytemuck::Pod>(
    r: &Read<'_>,
    name: &str,
    element: T,
    holds: &mut Holds,
) -> Result<Option<Buf<N>>, String> {
    r.array_of(name, element, |a| numbers(r, name, a, holds))
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
    vec3s(r, "vertex.position")?.ok_or_else(|| POSITION_REQUIRED.into())
}

/// `vertex.position`, in place where the host shares it: required.
pub fn shared_positions(r: &Read<'_>, holds: &mut Holds) -> Result<Buf<Vec3>, String> {
    shared(r, "vertex.position", T::FLOAT32_VEC3, holds)?.ok_or_else(|| POSITION_REQUIRED.into())
}

const POSITION_REQUIRED: &str = "parameter 'vertex.position' (ARRAY1D of FLOAT32_VEC3) is required";

/// The attributes and ids of a geometry of `vertices` vertices and
/// `primitives` host primitives, ready for the shape's checks; arrays
/// read in place join `holds`.
pub fn input(
    r: &Read<'_>,
    vertices: usize,
    primitives: usize,
    holds: &mut Holds,
) -> Result<ShapeInput, String> {
    let mut attributes: [Option<Attribute>; 5] = Default::default();
    for (slot, name) in ATTRIBUTE_NAMES.iter().enumerate() {
        let vertex = format!("vertex.{name}");
        let primitive = format!("primitive.{name}");
        attributes[slot] = match r.array(&primitive, |a| attribute(r, &primitive, a, holds))? {
            Some(v) => Some(Attribute::PerPrimitive(v)),
            None => r
                .array(&vertex, |a| attribute(r, &vertex, a, holds))?
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
