//! The counts of a Gmsh MSH 4.1 file, checked against the file's bytes before `mshio` reads it.
//!
//! `mshio` preallocates every list from the count written before it (entities, physical tags,
//! node and element blocks, nodes and elements per block): a count of 2^64 - 1 panics on the
//! capacity and one of 10^9 aborts on the allocation, whatever the file's size. This pass walks
//! the sections `mshio` reads (`$MeshFormat`, `$Entities`, `$Nodes`, `$Elements`) in the same
//! order, ASCII or binary, in time linear in the file, and refuses a count whose items cannot
//! fit in the bytes left: each item takes at least one byte and a separator in ASCII, and its
//! exact size in binary. Other sections are skipped as `mshio` skips them.

use num_traits::FromPrimitive as _;

/// The kinds of number of an MSH file, with their binary sizes (`size_t` set by the header).
#[derive(Clone, Copy)]
enum Item {
    SizeT,
    Int,
    Double,
}

/// A cursor over the file's bytes in the encoding its header declares.
struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
    /// Binary: the size of `size_t` and whether numbers are big-endian; `None` for ASCII.
    binary: Option<(usize, bool)>,
    /// The section being read, for messages.
    section: &'static str,
}

/// Checks every count of the MSH file `bytes`; the error names the section, the count and its
/// value.
pub fn check(bytes: &[u8]) -> Result<(), String> {
    let mut c = Cursor {
        bytes,
        pos: 0,
        binary: None,
        section: "$MeshFormat",
    };
    c.mesh_format()?;
    loop {
        c.skip_space();
        if c.pos == bytes.len() {
            return Ok(());
        }
        let name = c.section_start()?;
        match name.as_str() {
            "Entities" => c.within("$Entities", Cursor::entities)?,
            "Nodes" => c.within("$Nodes", Cursor::nodes)?,
            "Elements" => c.within("$Elements", Cursor::elements)?,
            _ => c.skip_section(&name)?,
        }
    }
}

impl<'a> Cursor<'a> {
    fn error(&self, what: impl std::fmt::Display) -> String {
        format!("section {}: {what} (at byte {})", self.section, self.pos)
    }

    fn skip_space(&mut self) {
        while self
            .bytes
            .get(self.pos)
            .is_some_and(|b| b" \t\r\n".contains(b))
        {
            self.pos += 1;
        }
    }

    /// The next whitespace-delimited word.
    fn word(&mut self) -> &'a [u8] {
        self.skip_space();
        let start = self.pos;
        while self
            .bytes
            .get(self.pos)
            .is_some_and(|b| !b" \t\r\n".contains(b))
        {
            self.pos += 1;
        }
        &self.bytes[start..self.pos]
    }

    /// `$MeshFormat` with version 4.1, the file type and the size of `size_t`; the endianness
    /// marker of a binary file.
    fn mesh_format(&mut self) -> Result<(), String> {
        if self.word() != b"$MeshFormat" {
            return Err("not an MSH file: it does not start with $MeshFormat".into());
        }
        let version = self.word();
        if version != b"4.1" {
            return Err(self.error(format!(
                "version {} (only MSH 4.1 is read)",
                String::from_utf8_lossy(version)
            )));
        }
        let file_type = self.word();
        let size_t = self.word();
        let size_t = match size_t {
            b"4" => 4,
            b"8" => 8,
            other => {
                return Err(self.error(format!(
                    "data size {} (expected 8, or 4)",
                    String::from_utf8_lossy(other)
                )))
            }
        };
        match file_type {
            b"0" => {}
            b"1" => {
                // the header line ends with one line break, then the integer 1 in binary
                self.pos += usize::from(self.bytes.get(self.pos) == Some(&b'\r'));
                self.pos += 1;
                let one = self
                    .bytes
                    .get(self.pos..self.pos + 4)
                    .ok_or_else(|| self.error("the file ends in the endianness marker"))?;
                let big = match one {
                    [0, 0, 0, 1] => true,
                    [1, 0, 0, 0] => false,
                    _ => return Err(self.error("no endianness marker (the integer 1)")),
                };
                self.pos += 4;
                self.binary = Some((size_t, big));
            }
            other => {
                return Err(self.error(format!(
                    "file type {} (expected 0 for ASCII or 1 for binary)",
                    String::from_utf8_lossy(other)
                )))
            }
        }
        if self.word() != b"$EndMeshFormat" {
            return Err(self.error("expected $EndMeshFormat"));
        }
        Ok(())
    }

    /// The name of the section starting here (`$Name` on its own line).
    fn section_start(&mut self) -> Result<String, String> {
        let word = self.word();
        match word.strip_prefix(b"$") {
            Some(name) if !name.is_empty() && name.iter().all(u8::is_ascii_alphabetic) => {
                Ok(String::from_utf8_lossy(name).into_owned())
            }
            _ => Err(format!(
                "expected a section such as $Nodes at byte {}, found {:?}",
                self.pos - word.len(),
                String::from_utf8_lossy(&word[..word.len().min(20)])
            )),
        }
    }

    /// Reads a section's body with `body`, then its end line `$End...`.
    fn within(
        &mut self,
        section: &'static str,
        body: fn(&mut Self) -> Result<(), String>,
    ) -> Result<(), String> {
        self.section = section;
        // the section line ends with one line break; a binary body starts right after it
        self.pos += usize::from(self.bytes.get(self.pos) == Some(&b'\r'));
        self.pos += 1;
        body(self)?;
        let end = format!("$End{}", &section[1..]);
        if self.word() != end.as_bytes() {
            return Err(self.error(format!(
                "expected {end}: the counts do not match the section's content"
            )));
        }
        Ok(())
    }

    /// Skips a section `mshio` does not read, up to its end line.
    fn skip_section(&mut self, name: &str) -> Result<(), String> {
        let end = format!("$End{name}");
        let rest = &self.bytes[self.pos..];
        let at = rest
            .windows(end.len())
            .position(|w| w == end.as_bytes())
            .ok_or_else(|| format!("section ${name} has no {end}"))?;
        self.pos += at + end.len();
        Ok(())
    }

    /// The least bytes an item takes: its size in binary, a digit and a separator in ASCII.
    fn min_bytes(&self, item: Item) -> u64 {
        match (self.binary, item) {
            (None, _) => 2,
            (Some((size_t, _)), Item::SizeT) => size_t as u64,
            (Some(_), Item::Int) => 4,
            (Some(_), Item::Double) => 8,
        }
    }

    /// One number of kind `item` named `what`, as an integer (a double is skipped and read as 0).
    fn number(&mut self, item: Item, what: &str) -> Result<i128, String> {
        let Some((_, big)) = self.binary else {
            let word = self.word();
            return match item {
                Item::Double => Ok(0),
                _ => std::str::from_utf8(word)
                    .ok()
                    .and_then(|w| w.parse::<i128>().ok())
                    .ok_or_else(|| {
                        self.error(format!(
                            "{what}: expected an integer, found {:?}",
                            String::from_utf8_lossy(&word[..word.len().min(24)])
                        ))
                    }),
            };
        };
        let size = self.min_bytes(item) as usize;
        let raw = self
            .bytes
            .get(self.pos..self.pos + size)
            .ok_or_else(|| self.error(format!("the file ends in {what}")))?;
        self.pos += size;
        let byte = |v: u64, &b: &u8| v << 8 | u64::from(b);
        let v = if big {
            raw.iter().fold(0, byte)
        } else {
            raw.iter().rev().fold(0, byte)
        };
        Ok(match item {
            Item::Double => 0,
            Item::Int => i128::from(v as u32 as i32),
            Item::SizeT => i128::from(v),
        })
    }

    /// A count of items each made of `items`, refused when they cannot fit in the bytes left.
    fn count(&mut self, what: &str, items: &[Item]) -> Result<u64, String> {
        let n = self.number(Item::SizeT, what)?;
        let each: u64 = items.iter().map(|&i| self.min_bytes(i)).sum();
        let left = (self.bytes.len() - self.pos) as u64;
        match u64::try_from(n) {
            Ok(n) if n.checked_mul(each).is_some_and(|b| b <= left) => Ok(n),
            _ => Err(self.error(format!(
                "{what} = {n} cannot fit in the {left} bytes left of the file (each needs at \
                 least {each} bytes); refused before reading"
            ))),
        }
    }

    /// Skips `n` items of kind `item`.
    fn skip(&mut self, n: u64, item: Item, what: &str) -> Result<(), String> {
        for _ in 0..n {
            self.number(item, what)?;
        }
        Ok(())
    }

    /// `$Entities`: points, curves, surfaces and volumes with their physical and bounding tags.
    fn entities(&mut self) -> Result<(), String> {
        use Item::{Double, Int, SizeT};
        let point = [Int, Double, Double, Double, SizeT];
        let other = [
            Int, Double, Double, Double, Double, Double, Double, SizeT, SizeT,
        ];
        let counts = [
            self.count("numPoints", &point)?,
            self.count("numCurves", &other)?,
            self.count("numSurfaces", &other)?,
            self.count("numVolumes", &other)?,
        ];
        for (kind, &n) in counts.iter().enumerate() {
            for _ in 0..n {
                self.skip(1, Int, "entity tag")?;
                self.skip(if kind == 0 { 3 } else { 6 }, Double, "coordinates")?;
                let tags = self.count("numPhysicalTags", &[Int])?;
                self.skip(tags, Int, "physical tags")?;
                if kind > 0 {
                    let bounding = self.count("numBounding entities", &[Int])?;
                    self.skip(bounding, Int, "bounding tags")?;
                }
            }
        }
        Ok(())
    }

    /// `$Nodes`: the blocks of node tags and coordinates.
    fn nodes(&mut self) -> Result<(), String> {
        use Item::{Double, Int, SizeT};
        let blocks = self.count("numEntityBlocks", &[Int, Int, Int, SizeT])?;
        let total = self.count("numNodes", &[SizeT, Double, Double, Double])?;
        if total == 0 {
            return Err(self.error("numNodes = 0: the mesh has no nodes"));
        }
        self.skip(2, SizeT, "min and max node tags")?;
        for _ in 0..blocks {
            self.skip(2, Int, "entity dimension and tag")?;
            if self.number(Int, "parametric")? != 0 {
                return Err(self.error("parametric nodes are not read"));
            }
            let n = self.count("numNodesInBlock", &[SizeT, Double, Double, Double])?;
            self.skip(n, SizeT, "node tags")?;
            self.skip(3 * n, Double, "node coordinates")?;
        }
        Ok(())
    }

    /// `$Elements`: the blocks of element tags and node tags.
    fn elements(&mut self) -> Result<(), String> {
        use Item::{Int, SizeT};
        let blocks = self.count("numEntityBlocks", &[Int, Int, Int, SizeT])?;
        let total = self.count("numElements", &[SizeT, SizeT])?;
        if total == 0 {
            return Err(self.error("numElements = 0: the mesh has no elements"));
        }
        self.skip(2, SizeT, "min and max element tags")?;
        for _ in 0..blocks {
            self.skip(2, Int, "entity dimension and tag")?;
            let kind = self.number(Int, "elementType")?;
            let nodes = i64::try_from(kind)
                .ok()
                .and_then(mshio::ElementType::from_i64)
                .and_then(|t| t.nodes().ok())
                .ok_or_else(|| self.error(format!("elementType = {kind} is not read")))?;
            let per_element = vec![SizeT; 1 + nodes];
            let n = self.count("numElementsInBlock", &per_element)?;
            self.skip(n * (1 + nodes as u64), SizeT, "element and node tags")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SQUARE: &str = super::super::tests::SQUARE;

    #[test]
    fn valid_files_pass_and_huge_counts_name_the_section_and_value() {
        assert_eq!(check(SQUARE.as_bytes()), Ok(()));
        let plate = std::fs::read(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/scripts/gmsh_plate.msh"
        ))
        .expect("plate");
        assert_eq!(check(&plate), Ok(()));
        let cases = [
            (
                "$Nodes\n1 4 1 4\n2 1 0 4\n",
                "$Nodes\n1 4 1 4\n2 1 0 18446744073709551615\n",
                "$Nodes: numNodesInBlock = 18446744073709551615",
            ),
            (
                "$Nodes\n1 4 1 4\n",
                "$Nodes\n1000000000 4 1 4\n",
                "$Nodes: numEntityBlocks = 1000000000",
            ),
            (
                "$Elements\n3 3 1 3\n",
                "$Elements\n3 99999999999 1 3\n",
                "$Elements: numElements = 99999999999",
            ),
            (
                "$Entities\n0 0 2 0\n",
                "$Entities\n0 0 1000000000 0\n",
                "$Entities: numSurfaces = 1000000000",
            ),
            (
                "1 0 0 0 1 1 0 1 7 0",
                "1 0 0 0 1 1 0 1000000000 7 0",
                "numPhysicalTags = 1000000000",
            ),
            ("4.1 0 8", "4.1 0 99999999999999999999999", "data size"),
            ("$Nodes\n1 4 1 4\n", "$Nodes\n1 0 1 4\n", "numNodes = 0"),
            (
                "2 1 0 4\n1\n2\n3\n4\n",
                "2 1 0 3\n1\n2\n3\n4\n",
                "counts do not match",
            ),
        ];
        for (from, to, needle) in cases {
            let text = SQUARE.replace(from, to);
            assert_ne!(text, SQUARE, "{from}");
            let e = check(text.as_bytes()).unwrap_err();
            assert!(e.contains(needle), "{to}: {e}");
        }
    }

    /// The square of the reader's tests as a binary MSH file.
    fn binary_square() -> Vec<u8> {
        let mut b = b"$MeshFormat\n4.1 1 8\n".to_vec();
        let size_t = |b: &mut Vec<u8>, v: &[u64]| v.iter().for_each(|x| b.extend(x.to_le_bytes()));
        let int = |b: &mut Vec<u8>, v: &[i32]| v.iter().for_each(|x| b.extend(x.to_le_bytes()));
        let double = |b: &mut Vec<u8>, v: &[f64]| v.iter().for_each(|x| b.extend(x.to_le_bytes()));
        int(&mut b, &[1]);
        b.extend_from_slice(b"\n$EndMeshFormat\n$Entities\n");
        size_t(&mut b, &[0, 0, 2, 0]);
        for (tag, group) in [(1, 7), (2, 8)] {
            int(&mut b, &[tag]);
            double(&mut b, &[0.0, 0.0, 0.0, 1.0, 1.0, 0.0]);
            size_t(&mut b, &[1]);
            int(&mut b, &[group]);
            size_t(&mut b, &[0]);
        }
        b.extend_from_slice(b"\n$EndEntities\n$Nodes\n");
        size_t(&mut b, &[1, 4, 1, 4]);
        int(&mut b, &[2, 1, 0]);
        size_t(&mut b, &[4, 1, 2, 3, 4]);
        double(
            &mut b,
            &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0],
        );
        b.extend_from_slice(b"\n$EndNodes\n$Elements\n");
        size_t(&mut b, &[3, 3, 1, 3]);
        for (dim, tag, kind, element) in [
            (2, 1, 2, &[1u64, 1, 2, 3][..]),
            (2, 2, 2, &[2, 1, 4, 3]),
            (1, 1, 1, &[3, 1, 2]),
        ] {
            int(&mut b, &[dim, tag, kind]);
            size_t(&mut b, &[1]);
            size_t(&mut b, element);
        }
        b.extend_from_slice(b"\n$EndElements\n");
        b
    }

    #[test]
    fn a_valid_binary_file_passes_and_reads() {
        let b = binary_square();
        assert_eq!(check(&b), Ok(()));
        let mesh = super::super::read_msh(&b, &std::collections::HashMap::from([(7, 0), (8, 1)]))
            .expect("mshio reads it");
        assert_eq!(mesh.triangles.len(), 2);
    }

    #[test]
    fn binary_counts_are_checked_too() {
        // $MeshFormat binary, then $Nodes with numEntityBlocks = 2^64 - 1
        let mut b = b"$MeshFormat\n4.1 1 8\n".to_vec();
        b.extend_from_slice(&1i32.to_le_bytes());
        b.extend_from_slice(b"\n$EndMeshFormat\n$Nodes\n");
        b.extend_from_slice(&u64::MAX.to_le_bytes());
        b.extend_from_slice(&[0; 24]);
        b.extend_from_slice(b"\n$EndNodes\n");
        let e = check(&b).unwrap_err();
        assert!(
            e.contains("$Nodes: numEntityBlocks = 18446744073709551615"),
            "{e}"
        );
    }
}
