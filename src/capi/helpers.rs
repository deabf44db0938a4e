//! `caveray.h`'s plain C helpers for hosts that drive ANARI's perspective
//! camera on CAVE walls (off-axis strategies 2 and 3) or need a wall's
//! OpenGL matrices.

use std::cell::RefCell;
use std::ffi::{c_char, CString};

use glam::{DMat4, DVec3, Mat4, Vec3};

use super::status::guard;
use super::sys::{
    ANARIStatusCode, CaverayPinhole, ANARI_STATUS_INVALID_ARGUMENT, ANARI_STATUS_NO_ERROR,
};
use crate::geometry::{pinhole_from_matrices as recover, OffAxisProjection, PinholeCamera, Screen};

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

fn finish(result: Result<(), String>) -> ANARIStatusCode {
    let (code, message) = match result {
        Ok(()) => (ANARI_STATUS_NO_ERROR, String::new()),
        Err(e) => (ANARI_STATUS_INVALID_ARGUMENT, e),
    };
    LAST_ERROR
        .with(|l| *l.borrow_mut() = CString::new(message.replace('\0', " ")).unwrap_or_default());
    code
}

/// Reads `N` floats from a host pointer, refusing NULL.
unsafe fn floats<const N: usize>(p: *const f32, what: &str) -> Result<[f32; N], String> {
    if p.is_null() {
        return Err(format!("{what} is NULL"));
    }
    Ok(std::ptr::read_unaligned(p.cast::<[f32; N]>()))
}

unsafe fn point(p: *const f32, what: &str) -> Result<DVec3, String> {
    Ok(Vec3::from(floats::<3>(p, what)?).as_dvec3())
}

fn to_c(c: &PinholeCamera) -> CaverayPinhole {
    let v = |d: DVec3| d.as_vec3().to_array();
    let r = c.image_region().to_array().map(|x| x as f32);
    CaverayPinhole {
        position: v(c.position()),
        direction: v(c.direction()),
        up: v(c.up()),
        fovy: c.fovy() as f32,
        aspect: c.aspect() as f32,
        imageRegion: r,
    }
}

unsafe fn screen(ll: *const f32, lr: *const f32, ur: *const f32) -> Result<Screen, String> {
    Screen::new(
        point(ll, "lowerLeft")?,
        point(lr, "lowerRight")?,
        point(ur, "upperRight")?,
    )
    .map_err(|e| e.to_string())
}

pub unsafe extern "C" fn pinhole_from_screen(
    ll: *const f32,
    lr: *const f32,
    ur: *const f32,
    eye: *const f32,
    out: *mut CaverayPinhole,
) -> ANARIStatusCode {
    let run = || -> Result<(), String> {
        if out.is_null() {
            return Err("out is NULL".into());
        }
        let screen = screen(ll, lr, ur)?;
        let camera =
            PinholeCamera::from_screen(&screen, point(eye, "eye")?).map_err(|e| e.to_string())?;
        out.write(to_c(&camera));
        Ok(())
    };
    guard(
        "caverayPinholeFromScreen",
        ANARI_STATUS_INVALID_ARGUMENT,
        || finish(run()),
    )
}

pub unsafe extern "C" fn pinhole_from_matrices(
    view: *const f32,
    proj: *const f32,
    out: *mut CaverayPinhole,
) -> ANARIStatusCode {
    let run = || -> Result<(), String> {
        if out.is_null() {
            return Err("out is NULL".into());
        }
        let view = Mat4::from_cols_array(&floats::<16>(view, "view")?).as_dmat4();
        let proj = Mat4::from_cols_array(&floats::<16>(proj, "proj")?).as_dmat4();
        let recovered = recover(view, proj).map_err(|e| e.to_string())?;
        out.write(to_c(&recovered.camera));
        Ok(())
    };
    guard(
        "caverayPinholeFromMatrices",
        ANARI_STATUS_INVALID_ARGUMENT,
        || finish(run()),
    )
}

#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn matrices_from_screen(
    ll: *const f32,
    lr: *const f32,
    ur: *const f32,
    eye: *const f32,
    near: f32,
    far: f32,
    view: *mut f32,
    proj: *mut f32,
) -> ANARIStatusCode {
    let run = || -> Result<(), String> {
        if view.is_null() || proj.is_null() {
            return Err("view or proj is NULL".into());
        }
        let screen = screen(ll, lr, ur)?;
        let p = OffAxisProjection::new(&screen, point(eye, "eye")?, near.into(), far.into())
            .map_err(|e| e.to_string())?;
        let write = |dst: *mut f32, m: DMat4| {
            // SAFETY: the host passes room for 16 floats.
            unsafe {
                dst.cast::<[f32; 16]>()
                    .write_unaligned(m.as_mat4().to_cols_array())
            }
        };
        write(view, p.view);
        write(proj, p.proj);
        Ok(())
    };
    guard(
        "caverayMatricesFromScreen",
        ANARI_STATUS_INVALID_ARGUMENT,
        || finish(run()),
    )
}

pub unsafe extern "C" fn last_error() -> *const c_char {
    LAST_ERROR.with(|l| l.borrow().as_ptr())
}
