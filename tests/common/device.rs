//! A host driving the device model directly (no C), on the CPU
//! reference: small volumes, frames and their pixels.

use std::sync::Arc;

use anari_library_caveray::scene::StructuredVolume;

use anari_library_caveray::device::{
    DataType, Device, Input, Severity, Status, StatusCode, Subject,
};

pub const SIZE: u32 = 24;

pub struct Host {
    pub d: Device,
    /// Messages taken from the device but not asked for yet.
    unread: Vec<Status>,
}

pub fn bytes<T: Copy>(values: &[T]) -> Vec<u8> {
    // SAFETY: plain numbers, read as their bytes.
    unsafe {
        std::slice::from_raw_parts(values.as_ptr().cast::<u8>(), std::mem::size_of_val(values))
    }
    .to_vec()
}

impl Host {
    pub fn new() -> Self {
        Self::reporting_to(Arc::new(|_s: Status| {}))
    }

    /// A host whose render thread's messages (which do not wait for the
    /// device's own list) go to `report`.
    pub fn reporting_to(report: anari_library_caveray::device::Reporter) -> Self {
        Self::on_backend("cpu", report)
    }

    /// A host of a device on `backend` ("cpu" or "gpu").
    pub fn on_backend(backend: &str, report: anari_library_caveray::device::Reporter) -> Self {
        let mut d = Device::new(report);
        d.set_param(Subject::Device, "backend", Input::String(backend.into()));
        d.commit(Subject::Device);
        Self {
            d,
            unread: Vec::new(),
        }
    }

    pub fn set(&mut self, object: u64, name: &str, ty: DataType, value: Vec<u8>) {
        self.d
            .set_param(Subject::Object(object), name, Input::Bytes(ty, value));
    }

    pub fn set_object(&mut self, object: u64, name: &str, ty: DataType, handle: u64) {
        self.d
            .set_param(Subject::Object(object), name, Input::Object(ty, handle));
    }

    /// A device-owned array filled with `data`.
    pub fn array(&mut self, kind: DataType, element: DataType, dims: [u64; 3], data: &[u8]) -> u64 {
        let a = self
            .d
            .new_array(kind, element as i32, dims, None)
            .ok()
            .unwrap();
        let ptr = self.d.map_array(a);
        // SAFETY: the device allocated dims * element size bytes.
        unsafe { std::ptr::copy_nonoverlapping(data.as_ptr(), ptr, data.len()) };
        self.d.unmap_array(a);
        a
    }

    /// A 4^3 field: `value(x)` along x, constant in y and z.
    pub fn field(&mut self, value: impl Fn(u32) -> f32, filter: Option<&str>) -> u64 {
        let voxels: Vec<f32> = (0..64).map(|i| value(i % 4)).collect();
        let data = self.array(
            DataType::ARRAY3D,
            DataType::FLOAT32,
            [4, 4, 4],
            &bytes(&voxels),
        );
        let f = self
            .d
            .new_object(DataType::SPATIAL_FIELD, "structuredRegular");
        self.set_object(f, "data", DataType::ARRAY3D, data);
        self.set(f, "origin", DataType::FLOAT32_VEC3, bytes(&[-1.0f32; 3]));
        self.set(
            f,
            "spacing",
            DataType::FLOAT32_VEC3,
            bytes(&[2.0f32 / 3.0; 3]),
        );
        if let Some(filter) = filter {
            self.d
                .set_param(Subject::Object(f), "filter", Input::String(filter.into()));
        }
        self.d.commit(Subject::Object(f));
        self.d.release(data);
        f
    }

    /// A `nanovdb` field of the grid `blob`, with `filter` if given.
    pub fn nanovdb_field(&mut self, blob: &[u8], filter: Option<&str>) -> u64 {
        let data = self.array(
            DataType::ARRAY1D,
            DataType::UINT8,
            [blob.len() as u64, 1, 1],
            blob,
        );
        let f = self.d.new_object(DataType::SPATIAL_FIELD, "nanovdb");
        self.set_object(f, "data", DataType::ARRAY1D, data);
        if let Some(filter) = filter {
            self.d
                .set_param(Subject::Object(f), "filter", Input::String(filter.into()));
        }
        self.d.commit(Subject::Object(f));
        self.d.release(data);
        f
    }

    /// `volume`'s FLOAT32 voxels as a `structuredRegular` field.
    pub fn structured_field(&mut self, volume: &StructuredVolume, filter: Option<&str>) -> u64 {
        let d = volume.dims();
        let values: Vec<f32> = (0..volume.voxels().len())
            .map(|i| volume.value(i))
            .collect();
        let data = self.array(
            DataType::ARRAY3D,
            DataType::FLOAT32,
            [d.x as u64, d.y as u64, d.z as u64],
            &bytes(&values),
        );
        let f = self
            .d
            .new_object(DataType::SPATIAL_FIELD, "structuredRegular");
        self.set_object(f, "data", DataType::ARRAY3D, data);
        self.set(
            f,
            "origin",
            DataType::FLOAT32_VEC3,
            bytes(&volume.origin().to_array()),
        );
        self.set(
            f,
            "spacing",
            DataType::FLOAT32_VEC3,
            bytes(&volume.spacing().to_array()),
        );
        if let Some(filter) = filter {
            self.d
                .set_param(Subject::Object(f), "filter", Input::String(filter.into()));
        }
        self.d.commit(Subject::Object(f));
        self.d.release(data);
        f
    }

    /// The 4^3 field of [`field`](Self::field) as an `unstructured` one:
    /// its 27 cells cut into six tetrahedra each (Kuhn), values at the
    /// vertices.
    pub fn mesh_field(&mut self, value: impl Fn(u32) -> f32) -> u64 {
        use anari_library_caveray::data::{cell_corners, KUHN};
        let at = |i: u32| -1.0 + 2.0 * i as f32 / 3.0;
        let mut positions = Vec::new();
        let mut values = Vec::new();
        for i in 0..64u32 {
            positions.extend([at(i % 4), at(i / 4 % 4), at(i / 16)]);
            values.push(value(i % 4));
        }
        let (mut index, mut cells, mut types) = (Vec::new(), Vec::new(), Vec::new());
        for c in 0..27u32 {
            let h = cell_corners(glam::UVec3::splat(4), c % 3, c / 3 % 3, c / 9);
            for t in KUHN {
                cells.push(index.len() as u32);
                types.push(10u8);
                index.extend(t.map(|k| h[k]));
            }
        }
        let arrays = [
            (
                "vertex.position",
                DataType::FLOAT32_VEC3,
                64,
                bytes(&positions),
            ),
            ("index", DataType::UINT32, index.len(), bytes(&index)),
            ("cell.index", DataType::UINT32, cells.len(), bytes(&cells)),
            ("cell.type", DataType::UINT8, types.len(), types.clone()),
            ("vertex.data", DataType::FLOAT32, 64, bytes(&values)),
        ];
        let f = self.d.new_object(DataType::SPATIAL_FIELD, "unstructured");
        for (name, element, n, data) in arrays {
            let a = self.array(DataType::ARRAY1D, element, [n as u64, 1, 1], &data);
            self.set_object(f, name, DataType::ARRAY1D, a);
            self.d.release(a);
        }
        self.d.commit(Subject::Object(f));
        f
    }

    /// The 4^3 field of [`field`](Self::field) as an `amr` one of two
    /// levels over the same box: a coarse block of 2^3 cells two units
    /// wide and a fine block of 4^3 cells under it, cell-centred values
    /// of the same ramp (value(x) at x = 0..3, interpolated between), in
    /// OpenCOVER's form (`cellWidth`, an ARRAY3D per block in an array
    /// declared ARRAY1D) or anari-visionaray's (`refinementRatio`, one
    /// `data`, `gridOrigin`/`gridSpacing`).
    pub fn amr_field(&mut self, value: impl Fn(u32) -> f32, opencover: bool) -> u64 {
        let ramp = |x: f32| {
            let i = (x.floor() as u32).min(2);
            let f = x - i as f32;
            value(i) * (1.0 - f) + value(i + 1) * f
        };
        // Fine cell i's centre is x = i (in grid units 0..3, cells 3/4
        // wide); coarse cell j's is x = 2 j + 0.5 in fine cells.
        let fine: Vec<f32> = (0..64).map(|i| ramp(((i % 4) as f32) * 1.0)).collect();
        let coarse: Vec<f32> = (0..8)
            .map(|j| ramp(((j % 2) as f32 * 2.0 + 0.5).min(3.0)))
            .collect();
        let bounds: [i32; 12] = [0, 0, 0, 3, 3, 3, 0, 0, 0, 1, 1, 1];
        let levels: [i32; 2] = [0, 1];
        let f = self.d.new_object(DataType::SPATIAL_FIELD, "amr");
        let list = |h: &mut Self, name: &str, element: DataType, n: u64, data: Vec<u8>| {
            let a = h.array(DataType::ARRAY1D, element, [n, 1, 1], &data);
            h.set_object(f, name, DataType::ARRAY1D, a);
            h.d.release(a);
        };
        list(
            self,
            "block.bounds",
            DataType::INT32_BOX3,
            2,
            bytes(&bounds),
        );
        list(self, "block.level", DataType::INT32, 2, bytes(&levels));
        // Fine cells 3/4 of a unit wide: the 4^3 field's vertices at
        // -1, -1/3, 1/3, 1 are the fine cells' centres.
        let spacing = 2.0f32 / 3.0;
        let origin = -1.0 - spacing / 2.0;
        if opencover {
            list(
                self,
                "cellWidth",
                DataType::FLOAT32,
                2,
                bytes(&[1.0f32, 2.0]),
            );
            let a = self.array(
                DataType::ARRAY3D,
                DataType::FLOAT32,
                [4, 4, 4],
                &bytes(&fine),
            );
            let b = self.array(
                DataType::ARRAY3D,
                DataType::FLOAT32,
                [2, 2, 2],
                &bytes(&coarse),
            );
            let handles = [a as usize, b as usize];
            list(self, "block.data", DataType::ARRAY1D, 2, bytes(&handles));
            self.d.release(a);
            self.d.release(b);
        } else {
            self.set(f, "refinementRatio", DataType::UINT32, bytes(&[2u32]));
            let all: Vec<f32> = fine.iter().chain(&coarse).copied().collect();
            list(self, "data", DataType::FLOAT32, 72, bytes(&all));
        }
        self.set(f, "gridOrigin", DataType::FLOAT32_VEC3, bytes(&[origin; 3]));
        self.set(
            f,
            "gridSpacing",
            DataType::FLOAT32_VEC3,
            bytes(&[spacing; 3]),
        );
        self.d.commit(Subject::Object(f));
        f
    }

    /// A frame showing `volume` head-on from `camera_z` on the z axis:
    /// (frame, camera).
    pub fn frame(&mut self, volume: u64, camera_z: f32) -> (u64, u64) {
        self.lit_frame(volume, camera_z, &[])
    }

    /// Sets `name` of `object` to an ARRAY1D of the `kind` objects
    /// `handles`, released again (the object keeps it).
    pub fn set_objects(&mut self, object: u64, name: &str, kind: DataType, handles: &[u64]) {
        let handles: Vec<usize> = handles.iter().map(|&h| h as usize).collect();
        let list = self.array(
            DataType::ARRAY1D,
            kind,
            [handles.len() as u64, 1, 1],
            &bytes(&handles),
        );
        self.set_object(object, name, DataType::ARRAY1D, list);
        self.d.release(list);
    }

    /// `frame`, with `lights` in the world's `light` array.
    pub fn lit_frame(&mut self, volume: u64, camera_z: f32, lights: &[u64]) -> (u64, u64) {
        self.d.commit(Subject::Object(volume));
        let list = self.array(
            DataType::ARRAY1D,
            DataType::VOLUME,
            [1, 1, 1],
            &bytes(&[volume as usize]),
        );
        let world = self.d.new_object(DataType::WORLD, "");
        self.set_object(world, "volume", DataType::ARRAY1D, list);
        if !lights.is_empty() {
            self.set_objects(world, "light", DataType::LIGHT, lights);
        }
        self.d.release(list);
        self.world_frame(world, camera_z)
    }

    /// Renders a world of `instances` head-on from z = 3 and returns RGBA8
    /// pixels.
    pub fn render_instances(&mut self, instances: &[u64]) -> Vec<u8> {
        let world = self.d.new_object(DataType::WORLD, "");
        self.set_objects(world, "instance", DataType::INSTANCE, instances);
        let (frame, camera) = self.world_frame(world, 3.0);
        let pixels = self.pixels(frame);
        self.d.release(frame);
        self.d.release(camera);
        pixels
    }

    /// A frame of `world` (released: the frame keeps it) seen from
    /// `camera_z` on the z axis: (frame, camera).
    fn world_frame(&mut self, world: u64, camera_z: f32) -> (u64, u64) {
        self.d.commit(Subject::Object(world));
        let renderer = self.d.new_object(DataType::RENDERER, "default");
        self.d.commit(Subject::Object(renderer));
        let camera = self.d.new_object(DataType::CAMERA, "perspective");
        self.set(
            camera,
            "position",
            DataType::FLOAT32_VEC3,
            bytes(&[0.0f32, 0.0, camera_z]),
        );
        self.d.commit(Subject::Object(camera));
        let frame = self.d.new_object(DataType::FRAME, "");
        self.set(frame, "size", DataType::UINT32_VEC2, bytes(&[SIZE, SIZE]));
        self.set(
            frame,
            "channel.color",
            DataType::DATA_TYPE,
            bytes(&[DataType::UFIXED8_VEC4 as i32]),
        );
        self.set_object(frame, "world", DataType::WORLD, world);
        self.set_object(frame, "renderer", DataType::RENDERER, renderer);
        self.set_object(frame, "camera", DataType::CAMERA, camera);
        self.d.commit(Subject::Object(frame));
        for h in [renderer, world] {
            self.d.release(h);
        }
        (frame, camera)
    }

    /// Renders `frame` and returns its RGBA8 pixels.
    pub fn pixels(&mut self, frame: u64) -> Vec<u8> {
        self.pixels_sized(frame, SIZE, SIZE)
    }

    /// Renders `frame`, `w` x `h`, and returns its RGBA8 pixels.
    pub fn pixels_sized(&mut self, frame: u64, w: u32, h: u32) -> Vec<u8> {
        self.d.render_frame(frame, None);
        let Some(mapped) = self.d.map_frame(frame, "channel.color") else {
            let said: Vec<String> = self
                .d
                .take_statuses()
                .into_iter()
                .map(|s| s.message)
                .collect();
            panic!("the frame did not render: {said:?}");
        };
        assert_eq!(mapped.size, glam::UVec2::new(w, h));
        // SAFETY: a mapped RGBA8 frame of w x h pixels, valid until unmap.
        let pixels =
            unsafe { std::slice::from_raw_parts(mapped.ptr, (4 * w * h) as usize) }.to_vec();
        self.d.unmap_frame(frame, "channel.color");
        pixels
    }

    /// The depth channel of rendered frame `frame`, `w` x `h`.
    pub fn depth_sized(&mut self, frame: u64, w: u32, h: u32) -> Vec<f32> {
        let mapped = self
            .d
            .map_frame(frame, "channel.depth")
            .expect("a depth channel");
        assert_eq!(mapped.size, glam::UVec2::new(w, h));
        // SAFETY: a mapped FLOAT32 channel of w x h values, valid until unmap.
        let d = unsafe { std::slice::from_raw_parts(mapped.ptr.cast::<f32>(), (w * h) as usize) }
            .to_vec();
        self.d.unmap_frame(frame, "channel.depth");
        d
    }

    /// Renders `volume` head-on and returns RGBA8 pixels.
    pub fn render(&mut self, volume: u64) -> Vec<u8> {
        let (frame, camera) = self.frame(volume, 3.0);
        let pixels = self.pixels(frame);
        self.d.release(frame);
        self.d.release(camera);
        pixels
    }

    /// A transferFunction1D volume over `field`.
    pub fn volume(&mut self, field: u64) -> u64 {
        let v = self.d.new_object(DataType::VOLUME, "transferFunction1D");
        self.set_object(v, "value", DataType::SPATIAL_FIELD, field);
        v
    }

    /// The messages of `severity` since the last ask for them; messages
    /// of other severities wait for their own ask.
    pub fn messages(&mut self, severity: Severity) -> Vec<String> {
        self.unread.extend(self.d.take_statuses());
        let (asked, rest): (Vec<Status>, Vec<Status>) =
            self.unread.drain(..).partition(|s| s.severity == severity);
        self.unread = rest;
        asked.into_iter().map(|s| s.message).collect()
    }

    /// The errors since the last ask for them, with their status codes.
    pub fn errors(&mut self) -> Vec<(StatusCode, String)> {
        self.unread.extend(self.d.take_statuses());
        let (asked, rest): (Vec<Status>, Vec<Status>) = self
            .unread
            .drain(..)
            .partition(|s| s.severity == Severity::Error);
        self.unread = rest;
        asked.into_iter().map(|s| (s.code, s.message)).collect()
    }
}

/// Whether two images are equal, reported by their first difference.
pub fn same(a: &[u8], b: &[u8]) -> Result<(), String> {
    match a.iter().zip(b).position(|(x, y)| x != y) {
        None if a.len() == b.len() => Ok(()),
        None => Err(format!("sizes {} and {}", a.len(), b.len())),
        Some(i) => Err(format!("byte {i} (pixel {}): {} vs {}", i / 4, a[i], b[i])),
    }
}

/// The centre pixel's RGB.
pub fn centre(pixels: &[u8]) -> [u8; 3] {
    let i = 4 * (SIZE / 2 * SIZE + SIZE / 2) as usize;
    [pixels[i], pixels[i + 1], pixels[i + 2]]
}
