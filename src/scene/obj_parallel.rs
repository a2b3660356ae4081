//! The common subset of OBJ read on every core: `v`, `vt`, `vn` and `f` lines, with the lines
//! tobj ignores (comments, `o`, `g`, `s`, unknown keywords), and no materials. tobj reads a file
//! line by line on one core, most of a large mesh's load (docs/benchmarks.md). Anything outside
//! the subset, or wrong in it, gives `None`, and the file is read by tobj, so that what a user is
//! told of a bad file is unchanged; on the subset both give the same triangles with the same
//! corners, normals and texture coordinates (tested against tobj's path).

use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// A file's triangles as `read_obj` gives a file without materials: the vertices its faces
/// name, in order of first use (as tobj orders them), and per triangle its corners' normals
/// and texture coordinates where the file has them.
pub(super) struct ObjTriangles {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    pub normals: Vec<Option<[Vec3; 3]>>,
    pub uvs: Vec<Option<[Vec2; 3]>>,
}

/// Text per parallel task: whole lines, about this many bytes.
const CHUNK_BYTES: usize = 1 << 20;

/// A corner's absent texture coordinate or normal.
const NONE: u32 = u32::MAX;

/// Which of a corner's texture coordinate and normal a face gives (bit 0, bit 1).
type Format = u8;

/// One chunk's lines read: its vertices, texture coordinates and normals, and its faces fanned
/// into triangles whose corners are (vertex, texture coordinate, normal) indices into the
/// whole file's.
#[derive(Default)]
struct Chunk {
    positions: Vec<Vec3>,
    uvs: Vec<Vec2>,
    normals: Vec<Vec3>,
    triangles: Vec<[[u32; 3]; 3]>,
    /// What every corner of the chunk gives, `None` without faces.
    format: Option<Format>,
}

/// `text` read, or `None` where tobj must read it.
pub(super) fn read(text: &str) -> Option<ObjTriangles> {
    let chunks = chunks(text);
    // What each chunk defines, so that each knows the counts its faces' indices refer to.
    let counts = chunks
        .par_iter()
        .map(|c| count(c))
        .collect::<Option<Vec<[u32; 3]>>>()?;
    let mut starts = Vec::with_capacity(chunks.len());
    let mut total = [0u32; 3];
    for c in &counts {
        starts.push(total);
        for k in 0..3 {
            total[k] = total[k].checked_add(c[k])?;
        }
    }
    let read = chunks
        .par_iter()
        .zip(&starts)
        .map(|(c, &start)| parse(c, start))
        .collect::<Option<Vec<Chunk>>>()?;
    // Every corner of the file must give the same: tobj makes up what a corner lacks where
    // the file has any (the first or the previous one), which this does not follow.
    let mut formats = read.iter().filter_map(|c| c.format);
    let format = formats.next()?;
    if formats.any(|f| f != format)
        || (format & 1 == 0 && total[1] > 0)
        || (format & 2 == 0 && total[2] > 0)
    {
        return None;
    }
    let positions: Vec<Vec3> = read
        .iter()
        .flat_map(|c| c.positions.iter().copied())
        .collect();
    let uvs: Vec<Vec2> = read.iter().flat_map(|c| c.uvs.iter().copied()).collect();
    let normals: Vec<Vec3> = read
        .iter()
        .flat_map(|c| c.normals.iter().copied())
        .collect();
    let corners: Vec<[[u32; 3]; 3]> = read.into_iter().flat_map(|c| c.triangles).collect();
    // The vertices faces name, in order of first use.
    let mut renumbered = vec![NONE; positions.len()];
    let mut used = Vec::new();
    let triangles = corners
        .iter()
        .map(|t| {
            t.map(|[v, _, _]| {
                let slot = &mut renumbered[v as usize];
                if *slot == NONE {
                    *slot = used.len() as u32;
                    used.push(positions[v as usize]);
                }
                *slot
            })
        })
        .collect();
    // As `read_obj` maps tobj's texture coordinates (no material: scale 1, offset 0, which
    // turns -0 into +0).
    let uv = |i: u32| uvs[i as usize] * Vec2::ONE + Vec2::ZERO;
    Some(ObjTriangles {
        positions: used,
        triangles,
        normals: corners
            .par_iter()
            .map(|t| (format & 2 != 0).then(|| t.map(|c| normals[c[2] as usize])))
            .collect(),
        uvs: corners
            .par_iter()
            .map(|t| (format & 1 != 0).then(|| t.map(|c| uv(c[1]))))
            .collect(),
    })
}

/// `text` cut after a line's end into pieces of about `CHUNK_BYTES`.
fn chunks(text: &str) -> Vec<&str> {
    let mut chunks = Vec::new();
    let mut rest = text;
    while rest.len() > CHUNK_BYTES {
        let end = match rest.as_bytes()[CHUNK_BYTES..]
            .iter()
            .position(|&b| b == b'\n')
        {
            Some(at) => CHUNK_BYTES + at + 1,
            None => rest.len(),
        };
        let (chunk, after) = rest.split_at(end);
        chunks.push(chunk);
        rest = after;
    }
    chunks.push(rest);
    chunks
}

/// A line's keyword and the words after it (tobj's reading: lines split at `\n`, words at
/// whitespace).
fn lines(chunk: &str) -> impl Iterator<Item = (&str, std::str::SplitWhitespace<'_>)> {
    chunk.split('\n').filter_map(|line| {
        let mut words = line.split_whitespace();
        words.next().map(|keyword| (keyword, words))
    })
}

/// How many vertices, texture coordinates and normals `chunk` defines; `None` where it has
/// what this reader leaves to tobj (materials; `l` and `p` lines, which tobj reads as faces).
fn count(chunk: &str) -> Option<[u32; 3]> {
    let mut counts = [0u32; 3];
    for (keyword, _) in lines(chunk) {
        match keyword {
            "v" => counts[0] += 1,
            "vt" => counts[1] += 1,
            "vn" => counts[2] += 1,
            "mtllib" | "usemtl" | "l" | "p" => return None,
            _ => {}
        }
    }
    Some(counts)
}

/// `chunk` read, its faces' indices counted from `start` (what the chunks before define).
fn parse(chunk: &str, start: [u32; 3]) -> Option<Chunk> {
    let mut read = Chunk::default();
    let mut corners: Vec<[u32; 3]> = Vec::new();
    for (keyword, mut words) in lines(chunk) {
        match keyword {
            "v" => {
                // Exactly three: a fourth (w) or three more (a colour) tobj reads its own way.
                let [x, y, z] = floats(&mut words)?;
                if words.next().is_some() {
                    return None;
                }
                read.positions.push(Vec3::new(x, y, z));
            }
            "vt" => {
                let [u, v] = floats(&mut words)?;
                read.uvs.push(Vec2::new(u, v));
            }
            "vn" => read.normals.push(Vec3::from_array(floats(&mut words)?)),
            "f" => {
                let defined = [
                    start[0] + read.positions.len() as u32,
                    start[1] + read.uvs.len() as u32,
                    start[2] + read.normals.len() as u32,
                ];
                corners.clear();
                for word in words {
                    let (corner, format) = corner(word, defined)?;
                    if *read.format.get_or_insert(format) != format {
                        return None;
                    }
                    corners.push(corner);
                }
                if corners.len() < 3 {
                    return None;
                }
                // A fan from the first corner, as tobj triangulates.
                for pair in corners[1..].windows(2) {
                    read.triangles.push([corners[0], pair[0], pair[1]]);
                }
            }
            _ => {}
        }
    }
    Some(read)
}

/// The first `N` words as floats (tobj reads these and ignores the rest).
fn floats<const N: usize>(words: &mut std::str::SplitWhitespace) -> Option<[f32; N]> {
    let mut values = [0.0; N];
    for value in &mut values {
        *value = words.next()?.parse().ok()?;
    }
    Some(values)
}

/// A face's corner `v`, `v/vt`, `v//vn` or `v/vt/vn` as indices into the whole file's lists,
/// where `defined` of each are defined so far (negative indices count back from there), and
/// which of vt and vn it gives.
fn corner(word: &str, defined: [u32; 3]) -> Option<([u32; 3], Format)> {
    let mut indices = [NONE; 3];
    let mut format = 0;
    for (k, part) in word.split('/').enumerate() {
        if k >= 3 {
            return None;
        }
        if part.is_empty() {
            if k == 0 {
                return None;
            }
            continue;
        }
        let i: i64 = part.parse().ok()?;
        let n = i64::from(defined[k]);
        indices[k] = if i > 0 && i <= n {
            i - 1
        } else if i < 0 && i >= -n {
            n + i
        } else {
            return None;
        } as u32;
        if k > 0 {
            format |= k as u8;
        }
    }
    Some((indices, format))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mesh this reader gives `text` is the one tobj's path gives (its faces' check
    /// included): each triangle's corners as points, normals and texture coordinates, bit for
    /// bit (vertex numbering may differ where tobj numbers each object apart), or the same
    /// error.
    fn assert_same(text: &str) {
        use super::super::mesh::{Mesh, read_obj_text, subset_mesh};
        let fast = subset_mesh("t.obj", read(text).expect("the subset reader reads it"));
        let slow = read_obj_text(std::path::Path::new("t.obj"), "t.obj", text).map(|mut parts| {
            assert_eq!(parts.len(), 1, "one part without materials");
            parts.remove(0)
        });
        let (fast, slow) = match (fast, slow) {
            (Ok(fast), Ok(slow)) => (fast, slow),
            (fast, slow) => {
                assert_eq!(fast.err(), slow.err(), "{text:?}");
                return;
            }
        };
        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
        let corners = |m: &Mesh| -> Vec<_> {
            (m.triangles.iter())
                .map(|t| t.map(|v| bits(m.positions[v as usize])))
                .collect()
        };
        assert_eq!(corners(&fast), corners(&slow), "{text:?}");
        let normal_bits = |m: &Mesh| -> Vec<_> { m.normals.iter().map(|n| n.map(bits)).collect() };
        assert_eq!(normal_bits(&fast), normal_bits(&slow), "{text:?}");
        let uv_bits = |m: &Mesh| -> Vec<_> {
            (m.uvs.iter())
                .map(|n| n.map(|uv| uv.to_array().map(f32::to_bits)))
                .collect()
        };
        assert_eq!(uv_bits(&fast), uv_bits(&slow), "{text:?}");
        assert_eq!(fast.extent.to_bits(), slow.extent.to_bits());
    }

    #[test]
    fn reads_what_tobj_reads() {
        // Every corner form, quads and a polygon fanned, negative indices, -0, comments, objects,
        // groups, smoothing, unknown keywords, CRLF, blank lines, trailing words tobj ignores.
        assert_same("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
        assert_same(
            "# a file\r\nmtl-less\nv 0 0 -0\nv 1 0 0\nv 1 1 0\n\nvt -0 0 7\nvt 1 0\nvt 1 1\r\n\
             vn 0 0 1\nvn 0 0.5 1 9\no one\ns 1\nf 1/1/1 2/2/1 3/3/2\ng two\nv 0 1 0\nv 2 2 0\n\
             vt 0 1\nf -5/-4/-2 -3/-2/-1 -2/-1/-1 -1/-1/-2 1/1/1\nvp 1 2\nf 3/1/2 2/2/1 4/4/1\n",
        );
        assert_same("v 1e3 2.5e-3 -4\nv 1 0 0\nv 0 1 0\nvn 1 0 0\nf 1//1 2//1 3//1\n");
        assert_same("v 1 2 3\nv 1 0 0\nv 0 1 0\nvt 0.5 0.25\nf 1/1 2/1 3/1\nf 3/1 2/1 1/1\n");
    }

    #[test]
    fn a_file_over_many_chunks_reads_as_tobj_reads_it() {
        // Faces name vertices of earlier chunks, by absolute and by negative indices.
        let mut text = String::new();
        let mut v = 0;
        for i in 0..120_000 {
            let (x, y) = ((i % 300) as f32 * 0.37, (i / 300) as f32 * 1.13);
            text += &format!("v {x} {y} {}\nvn 0 {} 1\n", (i % 7) as f32 - 3.0, i % 3);
            v += 1;
            if v >= 4 {
                text += &format!("f {0}//{0} -2//-1 {1}//{1}\n", v - 3, v);
                if i % 1000 == 0 {
                    text += "f 1//1 2//2 -1//-1 -3//-4\n";
                }
            }
        }
        assert!(chunks(&text).len() > 2);
        assert_same(&text);
    }

    #[test]
    fn random_files_read_as_tobj_reads_them_or_are_left_to_it() {
        // Small files of likely and unlikely lines: whatever this reader takes, tobj must
        // read the same way (and with tobj's own checks passing).
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = |n: u64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state % n
        };
        let (mut taken, mut left) = (0, 0);
        for _ in 0..4000 {
            // One corner form per file (mostly), the lists its corners name, then faces with
            // indices mostly in range, among lines of every other kind.
            let form = next(4);
            let mut counts = [0i64; 3];
            let mut text = String::new();
            let line = |text: &mut String, line: String, next: &mut dyn FnMut(u64) -> u64| {
                text.push_str(&line);
                text.push_str(if next(6) == 0 { "\r\n" } else { "\n" });
            };
            for _ in 0..3 + next(3) {
                line(
                    &mut text,
                    format!("v {} {} -{}", next(5), next(3), next(2)),
                    &mut next,
                );
                counts[0] += 1;
            }
            if form & 1 != 0 || next(10) == 0 {
                line(&mut text, format!("vt {} 0.5 1", next(2)), &mut next);
                counts[1] += 1;
            }
            if form & 2 != 0 || next(10) == 0 {
                line(&mut text, format!("vn 0 {} 1", next(2)), &mut next);
                counts[2] += 1;
            }
            for _ in 0..1 + next(6) {
                let l = match next(10) {
                    0 => {
                        counts[0] += 1;
                        format!("v {} {} 0", next(4), next(4))
                    }
                    1 => "o part\ns off\n# f 1 2 3".into(),
                    2 if next(5) == 0 => ["v 1 2", "f 1 2", "vt x 1", "v 1 2 3 4", "l 1 2 3"]
                        [next(5) as usize]
                        .into(),
                    _ => {
                        let form = if next(12) == 0 { next(4) } else { form };
                        let index = |k: usize, next: &mut dyn FnMut(u64) -> u64| {
                            let n = counts[k].max(1) as u64;
                            let i = next(n) as i64 + 1;
                            match next(12) {
                                0 => i + counts[k],
                                1..=4 => -i,
                                _ => i,
                            }
                        };
                        let count = 3 + next(3);
                        let corners = (0..count).map(|_| {
                            let (v, t, n) = (
                                index(0, &mut next),
                                index(1, &mut next),
                                index(2, &mut next),
                            );
                            match form {
                                0 => format!("{v}"),
                                1 => format!("{v}/{t}"),
                                2 => format!("{v}//{n}"),
                                _ => format!("{v}/{t}/{n}"),
                            }
                        });
                        format!("f {}", corners.collect::<Vec<_>>().join(" "))
                    }
                };
                line(&mut text, l, &mut next);
            }
            if read(&text).is_some() {
                assert_same(&text);
                taken += 1;
            } else {
                left += 1;
            }
        }
        // Both ways are exercised.
        assert!(
            taken > 200 && left > 200,
            "{taken} read, {left} left to tobj"
        );
    }

    #[test]
    fn leaves_to_tobj_what_it_reads_its_own_way() {
        for text in [
            "",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\n",
            "mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n",
            "v 0 0 0 1\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "v 0 0 0 1 1 1\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "v 0 0 x\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -9223372036854775808\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9223372036854775807\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 # a comment\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1/1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf /1 2 3\n",
            // Mixed corners, and normals no corner names: tobj makes up the missing ones.
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1 2 3\n",
        ] {
            assert!(read(text).is_none(), "{text:?}");
        }
    }
}
