//! Line-by-line validation of OBJ and MTL text before `tobj` loads it, so that every error
//! names its file, line and statement (tobj's own errors carry no line numbers).

use super::SceneError;
use std::collections::BTreeSet;
use std::path::Path;

/// What the OBJ pre-pass learned: the material names it uses and the MTL files it names.
#[derive(Debug, Default)]
pub struct ObjSummary {
    pub used_materials: BTreeSet<String>,
    pub mtllibs: Vec<String>,
}

fn parse_error(path: &Path, line: usize, message: String) -> SceneError {
    SceneError::Syntax {
        path: path.to_path_buf(),
        line,
        message,
    }
}

/// Largest vertex or camera coordinate accepted: squared distances of such points stay
/// finite in `f32`.
pub const MAX_COORDINATE: f64 = 1e15;

/// Parses `count` finite numbers from `words`; `what` names the statement for errors.
fn finite_numbers(
    path: &Path,
    line: usize,
    what: &str,
    words: &[&str],
    counts: &[usize],
) -> Result<Vec<f64>, SceneError> {
    if !counts.contains(&words.len()) {
        let want = counts
            .iter()
            .map(|c| c.to_string())
            .collect::<Vec<_>>()
            .join(" or ");
        return Err(parse_error(
            path,
            line,
            format!("`{what}` needs {want} numbers, found {}", words.len()),
        ));
    }
    words
        .iter()
        .map(|w| match w.parse::<f64>() {
            Ok(x) if x.is_finite() && x.abs() <= f32::MAX as f64 => Ok(x),
            Ok(_) => Err(parse_error(
                path,
                line,
                format!("`{what}`: non-finite number `{w}`"),
            )),
            Err(_) => Err(parse_error(
                path,
                line,
                format!("`{what}`: `{w}` is not a number"),
            )),
        })
        .collect()
}

/// The statements of an OBJ or MTL text: (1-based line, keyword, arguments), comments and
/// blank lines skipped.
fn statements(text: &str) -> impl Iterator<Item = (usize, &str, Vec<&str>)> {
    text.lines().enumerate().filter_map(|(i, raw)| {
        let content = raw.split('#').next().unwrap_or("");
        let mut words = content.split_whitespace();
        let keyword = words.next()?;
        Some((i + 1, keyword, words.collect()))
    })
}

/// Checks an OBJ file's statements: finite vertices, face indices in range, known
/// statements only.
pub fn check_obj(
    path: &Path,
    text: &str,
    warnings: &mut Vec<String>,
) -> Result<ObjSummary, SceneError> {
    let mut summary = ObjSummary::default();
    let mut vertices: i64 = 0;
    let mut warned = BTreeSet::new();
    for (line, keyword, args) in statements(text) {
        match keyword {
            "v" => {
                let v = finite_numbers(path, line, "v", &args, &[3, 4, 6])?;
                if let Some(x) = v[..3].iter().find(|x| x.abs() > MAX_COORDINATE) {
                    return Err(parse_error(
                        path,
                        line,
                        format!(
                            "`v`: coordinate {x} is beyond ±{MAX_COORDINATE:e} (squared distances must stay finite in single precision)"
                        ),
                    ));
                }
                vertices += 1;
            }
            "vn" => {
                finite_numbers(path, line, "vn", &args, &[3])?;
            }
            "vt" => {
                finite_numbers(path, line, "vt", &args, &[1, 2, 3])?;
            }
            "f" => {
                if args.len() < 3 {
                    return Err(parse_error(
                        path,
                        line,
                        format!("`f` needs at least 3 vertices, found {}", args.len()),
                    ));
                }
                for a in &args {
                    let index = a.split('/').next().unwrap_or("");
                    let k: i64 = index.parse().map_err(|_| {
                        parse_error(path, line, format!("`f`: `{a}` is not a vertex index"))
                    })?;
                    let in_range = if k > 0 {
                        k <= vertices
                    } else {
                        k < 0 && -k <= vertices
                    };
                    if !in_range {
                        return Err(parse_error(
                            path,
                            line,
                            format!("`f`: vertex index {k} out of range (1..={vertices} defined so far)"),
                        ));
                    }
                }
            }
            "usemtl" => {
                let name = args.join(" ");
                if name.is_empty() {
                    return Err(parse_error(
                        path,
                        line,
                        "`usemtl` needs a material name".into(),
                    ));
                }
                summary.used_materials.insert(name);
            }
            "mtllib" => {
                if args.is_empty() {
                    return Err(parse_error(path, line, "`mtllib` needs a file name".into()));
                }
                summary.mtllibs.push(args.join(" "));
            }
            "o" | "g" | "s" => {}
            "l" | "p" | "vp" | "cstype" | "deg" | "curv" | "surf" | "mg" | "usemap" => {
                if warned.insert(keyword) {
                    warnings.push(format!(
                        "{}:{line}: `{keyword}` statements are ignored",
                        path.display()
                    ));
                }
            }
            other => {
                return Err(parse_error(
                    path,
                    line,
                    format!("unknown OBJ statement `{other}`"),
                ));
            }
        }
    }
    Ok(summary)
}

/// Checks an MTL file's statements and returns the material names it defines.
pub fn check_mtl(
    path: &Path,
    text: &str,
    warnings: &mut Vec<String>,
) -> Result<BTreeSet<String>, SceneError> {
    let mut defined = BTreeSet::new();
    let mut current: Option<String> = None;
    let mut warned = BTreeSet::new();
    for (line, keyword, args) in statements(text) {
        let needs_material = |current: &Option<String>| {
            if current.is_none() {
                Err(parse_error(
                    path,
                    line,
                    format!("`{keyword}` before any `newmtl`"),
                ))
            } else {
                Ok(())
            }
        };
        match keyword {
            "newmtl" => {
                let name = args.join(" ");
                if name.is_empty() {
                    return Err(parse_error(path, line, "`newmtl` needs a name".into()));
                }
                if !defined.insert(name.clone()) {
                    return Err(parse_error(
                        path,
                        line,
                        format!("material `{name}` defined twice"),
                    ));
                }
                current = Some(name);
            }
            "Kd" | "Ks" | "Ke" => {
                needs_material(&current)?;
                let rgb = finite_numbers(path, line, keyword, &args, &[3])?;
                if rgb.iter().any(|&c| c < 0.0) {
                    return Err(parse_error(
                        path,
                        line,
                        format!("`{keyword}` must not be negative"),
                    ));
                }
                if keyword != "Ke" && rgb.iter().any(|&c| c > 1.0) {
                    return Err(parse_error(
                        path,
                        line,
                        format!("`{keyword}` is a reflectance and must lie in [0, 1]"),
                    ));
                }
            }
            "Ns" => {
                needs_material(&current)?;
                let ns = finite_numbers(path, line, "Ns", &args, &[1])?;
                if ns[0] < 0.0 {
                    return Err(parse_error(path, line, "`Ns` must not be negative".into()));
                }
            }
            "illum" => {
                needs_material(&current)?;
                let ok = args.len() == 1 && args[0].parse::<u8>().is_ok_and(|m| m <= 10);
                if !ok {
                    return Err(parse_error(
                        path,
                        line,
                        "`illum` needs one integer in 0..=10".into(),
                    ));
                }
            }
            "Ka" | "Ni" | "d" | "Tr" | "Tf" | "Pr" | "Pm" | "Ps" | "Pc" | "Pcr" | "aniso"
            | "anisor" | "sharpness" | "bump" | "disp" | "decal" | "refl" | "norm" => {
                if warned.insert(keyword.to_string()) {
                    warnings.push(format!(
                        "{}:{line}: `{keyword}` is not modelled by genpath and is ignored",
                        path.display()
                    ));
                }
            }
            k if k.starts_with("map_") => {
                if warned.insert(k.to_string()) {
                    warnings.push(format!(
                        "{}:{line}: texture `{k}` is not modelled by genpath and is ignored",
                        path.display()
                    ));
                }
            }
            other => {
                return Err(parse_error(
                    path,
                    line,
                    format!("unknown MTL statement `{other}`"),
                ));
            }
        }
    }
    Ok(defined)
}
