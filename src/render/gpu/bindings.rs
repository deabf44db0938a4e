//! Bind group tables: each binding of a group declared once, by name and
//! kind, from which come both the `wgpu::BindGroupLayoutEntry` list and
//! the WGSL `@group(g) @binding(n) var ...;` lines the shaders see (as
//! uniforms.rs does for structs). A binding's index is its place in the
//! table; the group's index is its place in the pipeline's list of groups,
//! so it is given when the WGSL is written.
//!
//! [`binding_table!`] defines a group's resources as a struct with one
//! field per binding, and a layout type made from the table: a bind group
//! is built from the struct, field by field in table order, so that a
//! resource cannot be bound at another binding's index, nor left out.

use wgpu::TextureViewDimension as Dim;

/// Every binding is used by compute passes.
const VISIBILITY: wgpu::ShaderStages = wgpu::ShaderStages::COMPUTE;

/// What a binding holds: the wgpu binding type and the WGSL type together.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Kind {
    /// `var<uniform> name: wgsl;`, `size` bytes read at a dynamic offset
    /// (per-frame parameters are storage buffers: see uniforms.rs).
    Uniform {
        wgsl: &'static str,
        size: u64,
    },
    /// `var<storage, read> name: wgsl;` or `read_write`.
    Storage {
        wgsl: &'static str,
        read_only: bool,
    },
    /// A sampled texture of f32 texels, filterable or not.
    Texture {
        dim: Dim,
        filterable: bool,
    },
    /// A write-only storage texture.
    StorageTexture {
        dim: Dim,
        format: wgpu::TextureFormat,
    },
    Sampler {
        filtering: bool,
    },
}

impl Kind {
    /// A uniform read at a dynamic offset, `size` bytes of it.
    pub const fn dynamic_uniform(wgsl: &'static str, size: u64) -> Self {
        Kind::Uniform { wgsl, size }
    }
    pub const fn storage(wgsl: &'static str) -> Self {
        Kind::Storage {
            wgsl,
            read_only: true,
        }
    }
    pub const fn storage_rw(wgsl: &'static str) -> Self {
        Kind::Storage {
            wgsl,
            read_only: false,
        }
    }
    pub const fn texture(dim: Dim, filterable: bool) -> Self {
        Kind::Texture { dim, filterable }
    }
    pub const fn write_texture(dim: Dim, format: wgpu::TextureFormat) -> Self {
        Kind::StorageTexture { dim, format }
    }
    pub const fn sampler(filtering: bool) -> Self {
        Kind::Sampler { filtering }
    }

    fn binding_type(self) -> wgpu::BindingType {
        match self {
            Kind::Uniform { size, .. } => wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: true,
                min_binding_size: wgpu::BufferSize::new(size),
            },
            Kind::Storage { read_only, .. } => wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            Kind::Texture { dim, filterable } => wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable },
                view_dimension: dim,
                multisampled: false,
            },
            Kind::StorageTexture { dim, format } => wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::WriteOnly,
                format,
                view_dimension: dim,
            },
            Kind::Sampler { filtering } => wgpu::BindingType::Sampler(if filtering {
                wgpu::SamplerBindingType::Filtering
            } else {
                wgpu::SamplerBindingType::NonFiltering
            }),
        }
    }

    /// `var<...> name: type` in WGSL.
    fn wgsl(self, name: &str) -> String {
        match self {
            Kind::Uniform { wgsl, .. } => format!("var<uniform> {name}: {wgsl}"),
            Kind::Storage { wgsl, read_only } => {
                let access = if read_only { "read" } else { "read_write" };
                format!("var<storage, {access}> {name}: {wgsl}")
            }
            Kind::Texture { dim, .. } => format!("var {name}: texture_{}<f32>", dim_wgsl(dim)),
            Kind::StorageTexture { dim, format } => format!(
                "var {name}: texture_storage_{}<{}, write>",
                dim_wgsl(dim),
                format_wgsl(format)
            ),
            Kind::Sampler { .. } => format!("var {name}: sampler"),
        }
    }
}

fn dim_wgsl(dim: Dim) -> &'static str {
    match dim {
        Dim::D1 => "1d",
        Dim::D2 => "2d",
        Dim::D2Array => "2d_array",
        Dim::Cube => "cube",
        Dim::CubeArray => "cube_array",
        Dim::D3 => "3d",
    }
}

/// The WGSL texel format of a storage texture; formats no pass uses are
/// named so that the shader fails to compile, saying which.
fn format_wgsl(format: wgpu::TextureFormat) -> &'static str {
    use wgpu::TextureFormat as F;
    match format {
        F::Rgba16Float => "rgba16float",
        F::Rgba32Float => "rgba32float",
        F::R32Float => "r32float",
        F::R32Uint => "r32uint",
        F::Rgba8Unorm => "rgba8unorm",
        _ => "unsupported_storage_format",
    }
}

/// One binding: its name in WGSL (and field name in Rust) and its kind.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Binding {
    pub name: &'static str,
    pub kind: Kind,
}

/// A bind group's bindings, binding n at index n, and the name of the
/// WGSL module that declares them (which imports `imports`, the modules
/// of the types it names).
#[derive(Clone, Debug, PartialEq)]
pub(super) struct BindingTable {
    pub module: &'static str,
    pub imports: &'static [&'static str],
    pub bindings: Vec<Binding>,
}

impl BindingTable {
    pub fn layout_entries(&self) -> Vec<wgpu::BindGroupLayoutEntry> {
        self.bindings
            .iter()
            .enumerate()
            .map(|(n, b)| wgpu::BindGroupLayoutEntry {
                binding: n as u32,
                visibility: VISIBILITY,
                ty: b.kind.binding_type(),
                count: None,
            })
            .collect()
    }

    /// The module declaring the bindings, as group `group`.
    pub fn wgsl(&self, group: u32) -> String {
        let mut out = format!("// Generated from the '{}' binding table.\n", self.module);
        if !self.imports.is_empty() {
            out += &format!("// #import {}\n", self.imports.join(", "));
        }
        for (n, b) in self.bindings.iter().enumerate() {
            out += &format!("@group({group}) @binding({n}) {};\n", b.kind.wgsl(b.name));
        }
        out
    }
}

/// A bind group layout and the table it was made from.
#[derive(Clone)]
pub(super) struct GroupLayout {
    table: BindingTable,
    layout: wgpu::BindGroupLayout,
}

impl GroupLayout {
    pub fn new(device: &wgpu::Device, table: BindingTable) -> Self {
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(table.module),
            entries: &table.layout_entries(),
        });
        Self { table, layout }
    }

    pub fn table(&self) -> &BindingTable {
        &self.table
    }

    pub fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// A bind group of `resources`, resource n at binding n; called by the
    /// resource structs of [`binding_table!`], which list them in table
    /// order.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        resources: Vec<wgpu::BindingResource<'_>>,
    ) -> wgpu::BindGroup {
        debug_assert_eq!(resources.len(), self.table.bindings.len());
        let entries: Vec<wgpu::BindGroupEntry> = resources
            .into_iter()
            .enumerate()
            .map(|(n, resource)| wgpu::BindGroupEntry {
                binding: n as u32,
                resource,
            })
            .collect();
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.table.module),
            layout: &self.layout,
            entries: &entries,
        })
    }
}

/// Declares a bind group once:
///
/// ```ignore
/// binding_table! {
///     /// What the group is for.
///     Resources / Layout = "module_name" imports ["struct_module"] (param: Type) {
///         /// What the binding holds.
///         name: Kind::storage("Struct"),
///         ...
///     }
/// }
/// ```
///
/// defines `Resources<'a>` (a `wgpu::BindingResource` per binding, with
/// `bind`), and `Layout` (the group layout, with `table(params)` and
/// `new(device, params)`). The parameters are what the kinds depend on at
/// run time (an adapter's filtering, a texel format).
macro_rules! binding_table {
    (
        $(#[$doc:meta])*
        $resources:ident / $layout:ident = $module:literal
        imports [$($import:literal),*] ($($param:ident: $pty:ty),*) {
            $($(#[$fdoc:meta])* $field:ident: $kind:expr,)*
        }
    ) => {
        $(#[$doc])*
        pub(super) struct $resources<'a> {
            $($(#[$fdoc])* pub $field: wgpu::BindingResource<'a>,)*
        }

        impl $resources<'_> {
            /// The bind group holding these resources.
            pub fn bind(self, device: &wgpu::Device, layout: &$layout) -> wgpu::BindGroup {
                layout.group().bind(device, vec![$(self.$field),*])
            }
        }

        #[doc = concat!("The layout of [`", stringify!($resources), "`], and its table.")]
        pub(super) struct $layout($crate::render::gpu::bindings::GroupLayout);

        impl $layout {
            pub fn table($($param: $pty),*) -> $crate::render::gpu::bindings::BindingTable {
                $crate::render::gpu::bindings::BindingTable {
                    module: $module,
                    imports: &[$($import),*],
                    bindings: vec![$($crate::render::gpu::bindings::Binding {
                        name: stringify!($field),
                        kind: $kind,
                    }),*],
                }
            }

            pub fn new(device: &wgpu::Device, $($param: $pty),*) -> Self {
                Self($crate::render::gpu::bindings::GroupLayout::new(
                    device,
                    Self::table($($param),*),
                ))
            }

            pub fn group(&self) -> &$crate::render::gpu::bindings::GroupLayout {
                &self.0
            }
        }
    };
}
pub(super) use binding_table;

/// Checks, by parsing, that WGSL `source` declares each of `groups`' tables
/// (group g at index g) as their layout entries say, and nothing else.
#[cfg(test)]
pub(super) fn assert_declared(source: &str, groups: &[&BindingTable]) {
    use wgpu::naga;
    let module = naga::front::wgsl::parse_str(source).unwrap_or_else(|e| {
        panic!("{}", e.emit_to_string(source));
    });
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)));
    let mut declared = 0;
    for (_, var) in module.global_variables.iter() {
        let Some(at) = &var.binding else {
            continue;
        };
        declared += 1;
        let name = var.name.as_deref().unwrap_or_default();
        let table = groups
            .get(at.group as usize)
            .unwrap_or_else(|| panic!("'{name}' is in group {}, which is not given", at.group));
        let entries = table.layout_entries();
        let entry = entries
            .get(at.binding as usize)
            .unwrap_or_else(|| panic!("'{name}': no binding {} in {}", at.binding, table.module));
        assert_eq!(name, table.bindings[at.binding as usize].name);
        let ty = &module.types[var.ty].inner;
        agree(name, &module, &var.space, ty, &entry.ty);
    }
    let tables: usize = groups.iter().map(|t| t.bindings.len()).sum();
    assert_eq!(declared, tables, "the shader declares other bindings");
}

/// Whether a WGSL global's address space and type fit a layout entry's
/// binding type.
#[cfg(test)]
fn agree(
    name: &str,
    module: &wgpu::naga::Module,
    space: &wgpu::naga::AddressSpace,
    ty: &wgpu::naga::TypeInner,
    binding: &wgpu::BindingType,
) {
    use wgpu::naga::{self, AddressSpace, ImageClass, ImageDimension, StorageAccess, TypeInner};
    let dim = |d: ImageDimension, arrayed: bool| match (d, arrayed) {
        (ImageDimension::D1, false) => Dim::D1,
        (ImageDimension::D2, false) => Dim::D2,
        (ImageDimension::D2, true) => Dim::D2Array,
        (ImageDimension::D3, false) => Dim::D3,
        (ImageDimension::Cube, false) => Dim::Cube,
        (ImageDimension::Cube, true) => Dim::CubeArray,
        other => panic!("'{name}': unexpected image {other:?}"),
    };
    match (space, ty, binding) {
        (
            AddressSpace::Uniform,
            _,
            wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                min_binding_size,
                ..
            },
        ) => {
            if let Some(size) = min_binding_size {
                let bytes = ty.size(module.to_ctx());
                assert_eq!(u64::from(bytes), size.get(), "'{name}': size");
            }
        }
        (
            AddressSpace::Storage { access },
            _,
            wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                ..
            },
        ) => assert_eq!(
            *read_only,
            !access.contains(StorageAccess::STORE),
            "'{name}': access"
        ),
        (
            AddressSpace::Handle,
            TypeInner::Image {
                dim: d,
                arrayed,
                class: ImageClass::Sampled { kind, multi },
            },
            wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { .. },
                view_dimension,
                multisampled,
            },
        ) => {
            assert_eq!(*kind, naga::ScalarKind::Float, "'{name}'");
            assert_eq!(multi, multisampled, "'{name}'");
            assert_eq!(dim(*d, *arrayed), *view_dimension, "'{name}'");
        }
        (
            AddressSpace::Handle,
            TypeInner::Image {
                dim: d,
                arrayed,
                class: ImageClass::Storage { format, access },
            },
            wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::WriteOnly,
                format: wanted,
                view_dimension,
            },
        ) => {
            assert_eq!(*access, StorageAccess::STORE, "'{name}'");
            assert_eq!(dim(*d, *arrayed), *view_dimension, "'{name}'");
            assert_eq!(format_wgsl(*wanted), format!("{format:?}").to_lowercase());
        }
        (
            AddressSpace::Handle,
            TypeInner::Sampler { comparison: false },
            wgpu::BindingType::Sampler(_),
        ) => {}
        other => panic!("'{name}': WGSL and the layout disagree: {other:?}"),
    }
}

#[cfg(test)]
#[allow(dead_code)]
mod tests {
    use super::*;

    binding_table! {
        /// A group with one binding of each kind.
        Every / EveryLayout = "every" imports [] (filterable: bool, format: wgpu::TextureFormat) {
            /// A struct from another module.
            thing: Kind::storage("Thing"),
            band: Kind::dynamic_uniform("vec4u", 16),
            source: Kind::storage("array<vec4f>"),
            counts: Kind::storage_rw("array<atomic<u32>>"),
            volume: Kind::texture(Dim::D3, filterable),
            layers: Kind::texture(Dim::D2Array, false),
            written: Kind::write_texture(Dim::D2Array, format),
            linear: Kind::sampler(filterable),
        }
    }

    binding_table! {
        BandOnly / BandOnlyLayout = "band_only" imports [] () {
            band_only: Kind::dynamic_uniform("vec4u", 16),
        }
    }

    fn with_thing(table: &BindingTable, group: u32) -> String {
        "struct Thing { a: vec4f, b: u32 }\n".to_string() + &table.wgsl(group)
    }

    #[test]
    fn the_wgsl_declares_what_the_layout_entries_say() {
        for (filterable, format) in [
            (true, wgpu::TextureFormat::Rgba16Float),
            (false, wgpu::TextureFormat::Rgba32Float),
        ] {
            let table = EveryLayout::table(filterable, format);
            assert_declared(&with_thing(&table, 0), &[&table]);
            let entries = table.layout_entries();
            assert_eq!(entries.len(), 8);
            for (n, e) in entries.iter().enumerate() {
                assert_eq!(e.binding, n as u32);
                assert_eq!(e.visibility, wgpu::ShaderStages::COMPUTE);
            }
            assert_eq!(
                entries[1].ty,
                wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: true,
                    min_binding_size: wgpu::BufferSize::new(16),
                }
            );
            assert_eq!(
                entries[4].ty,
                wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable },
                    view_dimension: Dim::D3,
                    multisampled: false,
                }
            );
        }
    }

    #[test]
    fn the_wgsl_lines_name_group_binding_and_type() {
        let table = EveryLayout::table(true, wgpu::TextureFormat::Rgba16Float);
        let text = table.wgsl(2);
        let lines: Vec<&str> = text.lines().filter(|l| l.starts_with('@')).collect();
        assert_eq!(
            lines,
            [
                "@group(2) @binding(0) var<storage, read> thing: Thing;",
                "@group(2) @binding(1) var<uniform> band: vec4u;",
                "@group(2) @binding(2) var<storage, read> source: array<vec4f>;",
                "@group(2) @binding(3) var<storage, read_write> counts: array<atomic<u32>>;",
                "@group(2) @binding(4) var volume: texture_3d<f32>;",
                "@group(2) @binding(5) var layers: texture_2d_array<f32>;",
                "@group(2) @binding(6) var written: texture_storage_2d_array<rgba16float, write>;",
                "@group(2) @binding(7) var linear: sampler;",
            ]
        );
        // A second group, declared at its own index.
        let band = BandOnlyLayout::table();
        assert!(band
            .wgsl(1)
            .contains("@group(1) @binding(0) var<uniform> band_only: vec4u;"));
        assert_declared(&(with_thing(&table, 0) + &band.wgsl(1)), &[&table, &band]);
    }

    #[test]
    #[should_panic(expected = "access")]
    fn a_disagreement_is_found() {
        let table = EveryLayout::table(true, wgpu::TextureFormat::Rgba16Float);
        let wrong = with_thing(&table, 0).replace(
            "var<storage, read> source",
            "var<storage, read_write> source",
        );
        assert_declared(&wrong, &[&table]);
    }

    #[test]
    fn imports_are_declared_for_the_resolver() {
        let table = BindingTable {
            module: "m",
            imports: &["ray_uniforms", "volume_slot"],
            bindings: vec![Binding {
                name: "params",
                kind: Kind::storage("RayUniforms"),
            }],
        };
        assert!(table
            .wgsl(0)
            .contains("// #import ray_uniforms, volume_slot\n"));
    }
}
