//! What hosts set on objects, through the device model: renderer subtypes
//! from a host's config, parameters hosts send that caveray has no use
//! for, and unknown ones (warned once per object and name).

use std::sync::Arc;

use anari_library_caveray::device::{
    DataType, Device, Input, Property, Severity, Status, StatusCode, Subject,
};

fn device() -> Device {
    Device::new(Arc::new(|_status: Status| {}))
}

fn messages(d: &mut Device, severity: Severity) -> Vec<String> {
    d.take_statuses()
        .into_iter()
        .filter(|s| s.severity == severity)
        .map(|s| s.message)
        .collect()
}

fn string(s: &str) -> Input {
    Input::String(s.to_owned())
}

#[test]
fn any_renderer_subtype_renders_as_the_default_renderer() {
    let mut d = device();
    for subtype in ["scivis", "dvr", "raycast", "pathtrace", "whatever"] {
        let r = d.new_object(DataType::RENDERER, subtype);
        let info = messages(&mut d, Severity::Info);
        assert!(
            info.len() == 1
                && info[0].contains(&format!(
                    "renderer '{subtype}' renders as caveray's 'default' renderer"
                )),
            "{subtype}: {info:?}"
        );
        d.set_param(Subject::Object(r), "shading", string("shadows"));
        d.commit(Subject::Object(r));
        let all = d.take_statuses();
        assert!(
            all.is_empty(),
            "{subtype}: {:?}",
            all.iter().map(|s| &s.message).collect::<Vec<_>>()
        );
    }
    // The default renderer itself is not announced.
    d.new_object(DataType::RENDERER, "default");
    assert!(d.take_statuses().is_empty());
    // Other kinds still name what is missing.
    d.new_object(DataType::CAMERA, "fisheye");
    let warnings = messages(&mut d, Severity::Warning);
    assert!(
        warnings[0].contains("does not implement camera 'fisheye'"),
        "{warnings:?}"
    );
}

#[test]
fn parameters_hosts_send_without_use_are_accepted_silently() {
    let mut d = device();
    let volume = d.new_object(DataType::VOLUME, "transferFunction1D");
    let camera = d.new_object(DataType::CAMERA, "perspective");
    for _ in 0..3 {
        d.set_param(Subject::Object(volume), "name", string("dataset 1"));
        d.set_param(
            Subject::Object(volume),
            "id",
            Input::Bytes(DataType::UINT32, 7u32.to_ne_bytes().to_vec()),
        );
        d.set_param(
            Subject::Object(camera),
            "apertureRadius",
            Input::Bytes(DataType::FLOAT32, 0f32.to_ne_bytes().to_vec()),
        );
        d.set_param(
            Subject::Object(camera),
            "focusDistance",
            Input::Bytes(DataType::FLOAT32, 1f32.to_ne_bytes().to_vec()),
        );
        d.set_param(Subject::Device, "name", string("caveray"));
    }
    let all = d.take_statuses();
    assert!(
        all.is_empty(),
        "{:?}",
        all.iter().map(|s| &s.message).collect::<Vec<_>>()
    );
}

#[test]
fn unknown_parameters_are_warned_once_per_object_and_name() {
    let mut d = device();
    let a = d.new_object(DataType::CAMERA, "perspective");
    let b = d.new_object(DataType::CAMERA, "perspective");
    let fov = || Input::Bytes(DataType::FLOAT32, 1f32.to_ne_bytes().to_vec());
    for _ in 0..5 {
        d.set_param(Subject::Object(a), "fov", fov());
        d.set_param(Subject::Object(b), "fov", fov());
        d.set_param(Subject::Object(a), "zoom", fov());
        d.set_param(Subject::Device, "verbose", fov());
    }
    let warnings = messages(&mut d, Severity::Warning);
    let count = |needle: &str| warnings.iter().filter(|w| w.contains(needle)).count();
    assert_eq!(warnings.len(), 4, "{warnings:?}");
    assert_eq!(count("has no parameter 'fov'"), 2, "{warnings:?}");
    assert_eq!(count("has no parameter 'zoom'"), 1, "{warnings:?}");
    assert_eq!(
        count("device has no parameter 'verbose'"),
        1,
        "{warnings:?}"
    );
    // A wrong type is still an error, every time.
    for _ in 0..2 {
        d.set_param(Subject::Object(a), "fovy", string("wide"));
    }
    let errors: Vec<_> = d
        .take_statuses()
        .into_iter()
        .filter(|s| s.severity == Severity::Error && s.code == StatusCode::InvalidArgument)
        .collect();
    assert_eq!(errors.len(), 2);
    assert!(d.property(Subject::Device, "version", false) == Some(Property::Int32(1)));
}

/// A renderer's FLOAT32 as the bytes a host passes.
fn float(x: f32) -> Input {
    Input::Bytes(DataType::FLOAT32, x.to_ne_bytes().to_vec())
}

#[test]
fn step_factor_and_sampling_rate_take_exactly_the_range_hosts_are_told() {
    use anari_library_caveray::device::info;
    let mut d = device();
    for name in ["stepFactor", "volumeSamplingRate"] {
        let (lo, hi) = info::param(DataType::RENDERER, "default", name)
            .and_then(|p| p.range)
            .unwrap_or_else(|| panic!("{name} states no range"));
        let r = d.new_object(DataType::RENDERER, "default");
        for ok in [lo, 1.0f32.clamp(lo, hi), hi] {
            d.set_param(Subject::Object(r), name, float(ok));
            d.commit(Subject::Object(r));
            let errors = messages(&mut d, Severity::Error);
            assert!(errors.is_empty(), "{name} {ok}: {errors:?}");
        }
        for bad in [lo * 0.99, hi * 1.01] {
            d.set_param(Subject::Object(r), name, float(bad));
            d.commit(Subject::Object(r));
            let errors = messages(&mut d, Severity::Error);
            assert!(
                errors.len() == 1
                    && errors[0]
                        .contains(&format!("{name} must be from {lo} to {hi}, got {bad:?}")),
                "{name} {bad}: {errors:?}"
            );
        }
        d.release(r);
    }
}

/// `caveray.mpi` takes "world" alone, and a build without the mpi feature
/// says how to get one; a world's `caveray.region` must be a box.
#[test]
fn the_mpi_mode_and_a_worlds_region_are_checked() {
    let mut d = device();
    d.set_param(Subject::Device, "caveray.mpi", string("universe"));
    d.commit(Subject::Device);
    let errors = messages(&mut d, Severity::Error);
    assert!(
        errors
            .iter()
            .any(|e| e.contains("'caveray.mpi': is 'universe'; the one value is \"world\"")),
        "{errors:?}"
    );
    #[cfg(not(feature = "mpi"))]
    {
        d.set_param(Subject::Device, "caveray.mpi", string("world"));
        d.commit(Subject::Device);
        let errors = messages(&mut d, Severity::Error);
        assert!(
            errors.iter().any(|e| e.contains(
                "this caveray was built without the mpi feature (cargo build --features mpi); frames render alone"
            )),
            "{errors:?}"
        );
    }
    let world = d.new_object(DataType::WORLD, "");
    let inverted: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, -1.0, 1.0]
        .iter()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    d.set_param(
        Subject::Object(world),
        "caveray.region",
        Input::Bytes(DataType::FLOAT32_BOX3, inverted),
    );
    d.commit(Subject::Object(world));
    let errors = messages(&mut d, Severity::Error);
    assert!(
        errors.iter().any(|e| {
            e.contains(
            "'caveray.region' must be a box with its lower corner below its upper one on every axis"
        )
        }),
        "{errors:?}"
    );
}
