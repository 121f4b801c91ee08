//! Wavefront MTL materials (the `mtllib` of an OBJ), read for a TOML `mesh` object whose material is
//! `{ kind = "mtl" }` (docs/scenes.md, "OBJ materials"): glass from `illum`, `Ni`, `d`/`Tr` and `Tf`, mirrors from
//! `illum`, diffuse surfaces from `Kd` and `map_Kd`. Parsed here rather than by tobj so that an error names the
//! file, the line and the statement.

use glam::{Vec2, Vec3};

/// One `newmtl` block: what the renderer reads of it, and where it was defined.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MtlMaterial {
    /// Its name (`newmtl NAME`).
    pub name: String,
    /// The MTL file that defines it (its `map_Kd` is relative to the file's folder).
    pub file: String,
    /// `FILE:LINE` of its `newmtl`, for messages.
    pub at: String,
    /// Diffuse reflectance (`Kd`).
    pub kd: Option<Vec3>,
    /// Emission (`Ke`): warned of when not black, since surfaces do not emit here.
    pub ke: Option<Vec3>,
    /// Index of refraction (`Ni`, "optical density").
    pub ni: Option<f32>,
    /// Dissolve (`d`, or 1 − `Tr`): the format's alpha, read only to warn that it is not drawn.
    pub dissolve: Option<f32>,
    /// Transmission filter (`Tf`): the color light keeps through the object.
    pub tf: Option<Vec3>,
    /// Illumination model (`illum`).
    pub illum: Option<u32>,
    /// The diffuse texture (`map_Kd`): its path as written (relative to the MTL file), its `-s` scale and `-o`
    /// offset (u, v).
    pub map_kd: Option<(String, Vec2, Vec2)>,
}

/// The `illum` models of the MTL format that let light through: 4 (transparency: glass on), 6 (refraction on), 7
/// (refraction and Fresnel on) and 9 (transparency: glass on, reflection off).
pub const TRANSPARENT_ILLUM: [u32; 4] = [4, 6, 7, 9];

/// The `illum` models that reflect as a mirror: 3 (reflection on, ray trace) and 5 (Fresnel mirror).
pub const MIRROR_ILLUM: [u32; 2] = [3, 5];

/// What a material is in the renderer's terms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    /// Glass: `illum` 4, 6, 7 or 9.
    Glass,
    /// A mirror: `illum` 3 or 5.
    Mirror,
    /// Anything else.
    Diffuse,
}

impl MtlMaterial {
    /// What the renderer makes of it (docs/scenes.md, "OBJ materials").
    pub fn kind(&self) -> Kind {
        let illum = self.illum.unwrap_or(2);
        if TRANSPARENT_ILLUM.contains(&illum) {
            Kind::Glass
        } else if MIRROR_ILLUM.contains(&illum) {
            Kind::Mirror
        } else {
            Kind::Diffuse
        }
    }
}

/// Parse MTL text; `file` names it in errors (`FILE:LINE: message`). Statements the renderer does not read (`Ka`,
/// `Ks`, `Ns`, other maps) are skipped.
pub fn parse(text: &str, file: &str) -> Result<Vec<MtlMaterial>, String> {
    let mut out: Vec<MtlMaterial> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        let at = || format!("{file}:{}", i + 1);
        let Some((key, rest)) = line.split_once(char::is_whitespace).or((!line.is_empty()).then_some((line, "")))
        else {
            continue;
        };
        let rest = rest.trim();
        let err = |what: &str| format!("{}: `{key}`: {what} (got `{rest}`)", at());
        if key == "newmtl" {
            if rest.is_empty() {
                return Err(err("needs a name"));
            }
            out.push(MtlMaterial { name: rest.to_string(), file: file.to_string(), at: at(), ..Default::default() });
            continue;
        }
        let known = ["Kd", "Ke", "Ni", "d", "Tr", "Tf", "illum", "map_Kd"];
        if !known.contains(&key) {
            continue;
        }
        let m = out.last_mut().ok_or_else(|| format!("{}: `{key}` before any `newmtl`", at()))?;
        let numbers = |n: usize| -> Result<Vec<f32>, String> {
            let v: Vec<f32> = rest
                .split_whitespace()
                .map(str::parse::<f32>)
                .collect::<Result<_, _>>()
                .map_err(|_| err(&format!("expected {n} number{}", if n > 1 { "s" } else { "" })))?;
            if v.len() != n && !(n == 3 && v.len() == 1) || v.iter().any(|x| !x.is_finite()) {
                return Err(err(&format!("expected {n} finite number{}", if n > 1 { "s" } else { "" })));
            }
            Ok(v)
        };
        // A color: three numbers, or one for gray; `spectral` and `xyz` forms are not read.
        let color = |lo: f32, hi: f32| -> Result<Vec3, String> {
            if rest.starts_with("spectral") || rest.starts_with("xyz") {
                return Err(err("only RGB colors are read (not `spectral` or `xyz`)"));
            }
            let v = numbers(3)?;
            let c = if v.len() == 1 { Vec3::splat(v[0]) } else { Vec3::new(v[0], v[1], v[2]) };
            if c.min_element() < lo || c.max_element() > hi {
                return Err(err(&format!("components must lie in [{lo}, {hi}]")));
            }
            Ok(c)
        };
        match key {
            "Kd" => m.kd = Some(color(0.0, 1.0)?),
            "Ke" => m.ke = Some(color(0.0, f32::MAX)?),
            "Tf" => m.tf = Some(color(0.0, 1.0)?),
            "Ni" => {
                let v = numbers(1)?[0];
                if v <= 0.0 {
                    return Err(err("the index of refraction must be > 0"));
                }
                m.ni = Some(v);
            }
            "d" | "Tr" => {
                // `d -halo f` is a dissolve that depends on the view: read as `f`.
                let v = rest.strip_prefix("-halo").map(str::trim).unwrap_or(rest);
                let x: f32 = v
                    .parse()
                    .ok()
                    .filter(|x: &f32| (0.0..=1.0).contains(x))
                    .ok_or_else(|| err("expected a number in [0, 1]"))?;
                m.dissolve = Some(if key == "d" { x } else { 1.0 - x });
            }
            "illum" => {
                let v: u32 =
                    rest.parse().ok().filter(|v| *v <= 10).ok_or_else(|| err("expected an integer in 0..=10"))?;
                m.illum = Some(v);
            }
            _ => m.map_kd = Some(texture_map(rest).map_err(|e| err(&e))?),
        }
    }
    Ok(out)
}

/// A texture statement's options and file name: `-s u [v [w]]` and `-o u [v [w]]` are read; `-bm`, `-blendu`,
/// `-clamp` and the others are skipped with their arguments; the rest of the line is the file name (which may
/// hold spaces).
fn texture_map(rest: &str) -> Result<(String, Vec2, Vec2), String> {
    let mut words = rest.split_whitespace().peekable();
    let (mut scale, mut offset) = (Vec2::ONE, Vec2::ZERO);
    // Each option and how many arguments it takes at most (`-s`/`-o`/`-t` take one to three numbers).
    while let Some(&w) = words.peek() {
        if !w.starts_with('-') || w.parse::<f32>().is_ok() {
            break;
        }
        words.next();
        let fixed = match w {
            "-blendu" | "-blendv" | "-cc" | "-clamp" | "-bm" | "-boost" | "-texres" | "-imfchan" | "-type" => 1,
            "-mm" => 2,
            "-s" | "-o" | "-t" => 0,
            other => return Err(format!("unknown texture option `{other}`")),
        };
        if fixed > 0 {
            for _ in 0..fixed {
                words.next().ok_or_else(|| format!("`{w}` needs {fixed} argument(s)"))?;
            }
            continue;
        }
        let mut v = Vec::new();
        while let Some(x) = words.peek().and_then(|x| x.parse::<f32>().ok()) {
            if v.len() == 3 {
                break;
            }
            v.push(x);
            words.next();
        }
        if v.is_empty() || v.iter().any(|x| !x.is_finite()) {
            return Err(format!("`{w}` needs one to three finite numbers"));
        }
        let uv = Vec2::new(v[0], *v.get(1).unwrap_or(&if w == "-s" { 1.0 } else { 0.0 }));
        match w {
            "-s" if uv.x == 0.0 || uv.y == 0.0 => return Err("`-s` must not be zero".into()),
            "-s" => scale = uv,
            "-o" => offset = uv,
            _ => {}
        }
    }
    let name = words.collect::<Vec<_>>().join(" ");
    if name.is_empty() {
        return Err("needs a file name".into());
    }
    Ok((name, scale, offset))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blender_and_classic_materials() {
        let text = "# Blender 3.4.1 MTL File\nnewmtl Floor\nKd 0.8 0.7 0.6\nNi 1.45\nd 1.0\nillum 2\n\
                    map_Kd -s 2 1 1 blocks.png\n\nnewmtl Glass\nNi 1.5\nTf 0.9 0.8 0.7\nillum 7\n\
                    newmtl Veil\nTr 0.25\nillum 9\nnewmtl Chrome\nillum 3\n";
        let m = parse(text, "a.mtl").unwrap();
        assert_eq!(m.len(), 4);
        assert_eq!(m[0].kind(), Kind::Diffuse);
        assert_eq!(m[0].kd, Some(Vec3::new(0.8, 0.7, 0.6)));
        assert_eq!(m[0].map_kd, Some(("blocks.png".into(), Vec2::new(2.0, 1.0), Vec2::ZERO)));
        assert_eq!(m[0].at, "a.mtl:2");
        assert_eq!((m[1].kind(), m[1].ni, m[1].tf), (Kind::Glass, Some(1.5), Some(Vec3::new(0.9, 0.8, 0.7))));
        assert_eq!((m[2].kind(), m[2].dissolve), (Kind::Glass, Some(0.75)));
        assert_eq!(m[3].kind(), Kind::Mirror);
    }

    #[test]
    fn errors_name_the_line_and_statement() {
        for (text, needle) in [
            ("Kd 1 1 1\n", "a.mtl:1: `Kd` before any `newmtl`"),
            ("newmtl A\nKd 1 x 1\n", "a.mtl:2: `Kd`: expected 3 numbers"),
            ("newmtl A\nKd 1 2 1\n", "a.mtl:2: `Kd`: components must lie in [0, 1]"),
            ("newmtl A\n\nNi -1\n", "a.mtl:3: `Ni`: the index of refraction must be > 0"),
            ("newmtl A\nd 2\n", "a.mtl:2: `d`: expected a number in [0, 1]"),
            ("newmtl A\nillum 12\n", "a.mtl:2: `illum`: expected an integer in 0..=10"),
            ("newmtl A\nmap_Kd -s 0 1 x.png\n", "a.mtl:2: `map_Kd`: `-s` must not be zero"),
            ("newmtl A\nmap_Kd -q x.png\n", "unknown texture option `-q`"),
            ("newmtl A\nmap_Kd -s 2\n", "needs a file name"),
            ("newmtl\n", "a.mtl:1: `newmtl`: needs a name"),
        ] {
            let e = parse(text, "a.mtl").unwrap_err();
            assert!(e.contains(needle), "{text:?}: {e}");
        }
    }
}
