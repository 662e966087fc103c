//! Reading an object's mesh from a file: Wavefront OBJ (through `tobj`, polygons
//! triangulated) or PLY (through `ply-rs-bw`, ASCII or binary: a `vertex` element with `x y
//! z` and a `face` element with a `vertex_indices` or `vertex_index` list, polygons fanned).

use std::path::Path;

use ply_rs_bw::ply::Property;

use super::{LocalMesh, ObjectError};

/// The mesh in `path`, by its extension (`.obj` or `.ply`).
pub fn read_mesh(path: &Path) -> Result<LocalMesh, ObjectError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let bad = |message: String| ObjectError::Mesh {
        path: path.into(),
        message,
    };
    let mesh = match ext.as_deref() {
        Some("obj") => read_obj(path).map_err(bad)?,
        Some("ply") => read_ply(path).map_err(bad)?,
        _ => return Err(bad("not a .obj or .ply file".into())),
    };
    mesh.check().map_err(bad)?;
    Ok(mesh)
}

fn read_obj(path: &Path) -> Result<LocalMesh, String> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) = tobj::load_obj(path, &options).map_err(|e| e.to_string())?;
    let mut m = LocalMesh::default();
    for model in models {
        let base = m.positions.len() as u32;
        m.positions.extend(
            model
                .mesh
                .positions
                .chunks_exact(3)
                .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64]),
        );
        m.triangles.extend(
            model
                .mesh
                .indices
                .chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
    }
    Ok(m)
}

fn read_ply(path: &Path) -> Result<LocalMesh, String> {
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut reader = std::io::BufReader::new(file);
    let parser = ply_rs_bw::parser::Parser::<ply_rs_bw::ply::DefaultElement>::new();
    let ply = parser.read_ply(&mut reader).map_err(|e| e.to_string())?;
    let vertices = ply.payload.get("vertex").ok_or("no `vertex` element")?;
    let mut m = LocalMesh::default();
    for (i, v) in vertices.iter().enumerate() {
        let mut p = [0.0; 3];
        for (c, key) in p.iter_mut().zip(["x", "y", "z"]) {
            *c = v
                .get(key)
                .and_then(scalar)
                .ok_or_else(|| format!("vertex {i} has no number `{key}`"))?;
        }
        m.positions.push(p);
    }
    let faces = ply.payload.get("face").ok_or("no `face` element")?;
    for (i, f) in faces.iter().enumerate() {
        let list = f
            .get("vertex_indices")
            .or_else(|| f.get("vertex_index"))
            .and_then(index_list)
            .ok_or_else(|| format!("face {i} has no `vertex_indices` list"))?;
        if list.len() < 3 {
            return Err(format!("face {i} has {} vertices (at least 3)", list.len()));
        }
        for k in 1..list.len() - 1 {
            m.triangles.push([list[0], list[k], list[k + 1]]);
        }
    }
    Ok(m)
}

fn scalar(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Float(v) => v as f64,
        Property::Double(v) => v,
        Property::Char(v) => v as f64,
        Property::UChar(v) => v as f64,
        Property::Short(v) => v as f64,
        Property::UShort(v) => v as f64,
        Property::Int(v) => v as f64,
        Property::UInt(v) => v as f64,
        _ => return None,
    })
}

fn index_list(p: &Property) -> Option<Vec<u32>> {
    let signed = |v: &[i64]| v.iter().map(|&i| u32::try_from(i).ok()).collect();
    match p {
        Property::ListInt(v) => signed(&v.iter().map(|&i| i as i64).collect::<Vec<_>>()),
        Property::ListUInt(v) => Some(v.clone()),
        Property::ListShort(v) => signed(&v.iter().map(|&i| i as i64).collect::<Vec<_>>()),
        Property::ListUShort(v) => Some(v.iter().map(|&i| i as u32).collect()),
        Property::ListChar(v) => signed(&v.iter().map(|&i| i as i64).collect::<Vec<_>>()),
        Property::ListUChar(v) => Some(v.iter().map(|&i| i as u32).collect()),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same unit square (two triangles) as OBJ and as ASCII PLY reads to the same mesh;
    /// a face that names a vertex the file does not hold is refused with its number.
    #[test]
    fn obj_and_ply_read_the_same_square() {
        let dir = std::env::temp_dir().join(format!("vastocean-load-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let obj = dir.join("square.obj");
        std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nf 1 2 3 4\n").unwrap();
        let ply = dir.join("square.ply");
        std::fs::write(
            &ply,
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
             property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
             end_header\n0 0 0\n1 0 0\n1 0 1\n0 0 1\n4 0 1 2 3\n",
        )
        .unwrap();
        let a = read_mesh(&obj).unwrap();
        let b = read_mesh(&ply).unwrap();
        assert_eq!(a.positions, b.positions);
        assert_eq!(a.triangles.len(), 2);
        assert_eq!(a.triangles, b.triangles);
        let broken = dir.join("broken.ply");
        std::fs::write(
            &broken,
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
             end_header\n0 0 0\n1 0 0\n1 0 1\n3 0 1 7\n",
        )
        .unwrap();
        let e = read_mesh(&broken).unwrap_err().to_string();
        assert!(e.contains("broken.ply") && e.contains('7'), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
