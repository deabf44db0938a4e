//! VTK unstructured grids as meshio (XML `.vtu` as text, base64 binary
//! with and without zlib; legacy `.vtk` 4.2 and 5.1, ASCII and binary)
//! and pyevtk (`.vtu` with raw appended data) write them, made at test
//! time: one cell of each kind and a triangle beside them, a linear field
//! at the points and a value per cell. Every cell holds the field at its
//! centroid, the cell data is constant in each cell, the triangle is left
//! out, and bad files are refused by the field at fault.

use glam::Vec3;

use crate::fixtures;
use anari_library_caveray::data::{is_vtk_mesh, load_vtk_mesh, parse_vtk_mesh};
use anari_library_caveray::scene::CellKind;

/// The cells (VTK order), the field f(p) = 1 + x + 2y - 0.5z at the
/// points, a value per cell, written every way the writers have.
const WRITE: &str = r#"
import json
import numpy as np, meshio
from pyevtk.hl import unstructuredGridToVTK
from pyevtk.vtk import VtkTetra, VtkHexahedron, VtkWedge, VtkPyramid, VtkTriangle
pts = np.array([
    [0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1],
    [1.5, 0, 0], [2.5, 0, 0], [2.5, 1, 0], [1.5, 1, 0], [1.5, 0, 1], [2.5, 0, 1], [2.5, 1, 1], [1.5, 1, 1],
    [3, 0, 0], [4, 0, 0], [3, 1, 0], [3, 0, 1], [4, 0, 1], [3, 1, 1],
    [4.5, 0, 0], [5.5, 0, 0], [5.5, 1, 0], [4.5, 1, 0], [5, 0.5, 1],
], dtype=np.float64)
f = 1 + pts[:, 0] + 2 * pts[:, 1] - 0.5 * pts[:, 2]
cells = [("tetra", [[0, 1, 2, 3]]), ("hexahedron", [list(range(4, 12))]),
         ("wedge", [list(range(12, 18))]), ("pyramid", [list(range(18, 23))]),
         ("triangle", [[0, 1, 2]])]
per_cell = [[10.0], [20.0], [30.0], [40.0], [50.0]]
mesh = meshio.Mesh(pts, cells, point_data={"f": f}, cell_data={"id": per_cell})
out = {}
for name, kw in [("ascii.vtu", dict(binary=False)), ("zlib.vtu", dict(binary=True, compression="zlib")),
                 ("plain.vtu", dict(binary=True, compression=None))]:
    meshio.write(name, mesh, **kw)
    out[name] = "xml"
for name, kw in [("legacy42_binary.vtk", dict(binary=True, fmt_version="4.2")),
                 ("legacy42_ascii.vtk", dict(binary=False, fmt_version="4.2")),
                 ("legacy51_binary.vtk", dict(binary=True, fmt_version="5.1")),
                 ("legacy51_ascii.vtk", dict(binary=False, fmt_version="5.1"))]:
    meshio.vtk.write(name, mesh, **kw)
    out[name] = "legacy"
conn = np.concatenate([np.array(c[1][0]) for c in cells]).astype(np.int64)
offsets = np.cumsum([len(c[1][0]) for c in cells]).astype(np.int64)
types = np.array([VtkTetra.tid, VtkHexahedron.tid, VtkWedge.tid, VtkPyramid.tid, VtkTriangle.tid], dtype=np.uint8)
unstructuredGridToVTK("./raw", pts[:, 0].copy(), pts[:, 1].copy(), pts[:, 2].copy(), conn, offsets, types,
                      pointData={"f": f.copy()}, cellData={"id": np.array([10.0, 20, 30, 40, 50])})
out["raw.vtu"] = "xml"
print(json.dumps(out))
"#;

fn field(p: Vec3) -> f32 {
    1.0 + p.x + 2.0 * p.y - 0.5 * p.z
}

/// Centroids of the four solid cells, in the order written.
fn centroids() -> [Vec3; 4] {
    [
        Vec3::new(0.25, 0.25, 0.25),
        Vec3::new(2.0, 0.5, 0.5),
        Vec3::new(10.0 / 3.0, 1.0 / 3.0, 0.5),
        Vec3::new(5.0, 0.5, 0.2),
    ]
}

#[test]
fn meshio_and_pyevtk_grids_hold_their_fields_in_every_cell() {
    let Some((dir, files)) = fixtures::written_by("meshio and pyevtk", WRITE, "vtk_mesh") else {
        return;
    };
    let files = files.as_object().unwrap();
    assert_eq!(files.len(), 8);
    for (name, flavour) in files {
        let path = dir.join(name);
        let bytes = std::fs::read(&path).unwrap();
        assert!(
            is_vtk_mesh(&bytes),
            "{name} is not seen as an unstructured grid"
        );
        let points = load_vtk_mesh(&path, None).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(points.flavour, flavour.as_str().unwrap(), "{name}");
        assert_eq!(points.array, "f", "{name}");
        assert!(!points.at_cells);
        assert_eq!(points.skipped, 1, "{name}: the triangle is left out");
        let counts = points.mesh.cell_counts();
        assert!(counts.iter().all(|(_, n)| *n == 1), "{name}: {counts:?}");
        assert_eq!(counts[0].0, CellKind::Tetrahedron);
        for c in centroids() {
            let got = points.mesh.sample(c);
            assert!(
                (got - field(c)).abs() < 1e-4,
                "{name} at {c}: {got} vs {}",
                field(c)
            );
        }
        let cells = load_vtk_mesh(&path, Some("id")).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(cells.at_cells, "{name}");
        for (c, want) in centroids().into_iter().zip([10.0, 20.0, 30.0, 40.0]) {
            assert_eq!(cells.mesh.sample(c), want, "{name} at {c}");
        }
        let err = load_vtk_mesh(&path, Some("nothing"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("no array named 'nothing'"), "{name}: {err}");
    }
}

#[test]
fn bad_grids_are_refused_by_the_field_at_fault() {
    let file = |cells: &str, types: &str| {
        format!(
            "# vtk DataFile Version 4.2\nbad\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 1 5\n{cells}\nCELL_TYPES 1\n{types}\nPOINT_DATA 4\nSCALARS f float 1\nLOOKUP_TABLE default\n1 2 3 4\n"
        )
    };
    let refused = |text: String| {
        parse_vtk_mesh(text.as_bytes(), "bad.vtk", None)
            .unwrap_err()
            .to_string()
    };
    assert!(parse_vtk_mesh(file("4 0 1 2 3", "10").as_bytes(), "good.vtk", None).is_ok());
    let e = refused(file("4 0 1 2 9", "10"));
    assert!(
        e.contains("index[3] = 9 is past the 4 vertex positions"),
        "{e}"
    );
    let e = refused(file("4 0 1 2 3", "24"));
    assert!(e.contains("cell 0 is a quadratic tetrahedron"), "{e}");
    let e = refused(file("4 0 1 2 3", "12"));
    assert!(
        e.contains("cell 0 (VTK type 12) has 4 points; it needs 8"),
        "{e}"
    );
    let e = refused(file("9 0 1 2 3", "10"));
    assert!(e.contains("cell 0 claims 9 points"), "{e}");
    let e = refused("# vtk DataFile Version 4.2\nx\nASCII\nDATASET STRUCTURED_POINTS\n".into());
    assert!(e.contains("this reader takes UNSTRUCTURED_GRID"), "{e}");
    let e = refused(
        "# vtk DataFile Version 4.2\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 999999999999 float\n".into(),
    );
    assert!(e.contains("vertex.position"), "{e}");
}
