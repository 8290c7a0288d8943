//! Gmsh `.msh` writer: ASCII 4.1 and 2.2, binary 4.1.
//!
//! Numbering and tags, identical in every version:
//! * node `i` of the mesh gets tag `i + 1`; tet `t` gets element tag `t + 1`; the labelled
//!   triangles follow, grouped by label in tag order (mesh order within a label), with tags
//!   `#T + 1, …`;
//! * physical groups of one interval: surfaces `alpha` = 1, `beta` = 2, `box` = 3
//!   (dimension 2, only the labels that occur) and volume `domain` = 4 (dimension 3); the
//!   elementary entity of a surface has the same tag as its physical group, the volume
//!   entity has tag 1;
//! * several regions (a run of `n` levels): surfaces `level1` = 1 … `level<n>` = n and
//!   `box` = n + 1 (the label's [`BoundaryLabel::code`] plus one; the interfaces between
//!   regions are the surfaces of the inner levels, each triangle oriented out of the region
//!   below); per region `k` (counting from 0) that has tets, a volume entity and physical
//!   group of tag `k + 1` named by the region's name (`region1`, … by default). Its tets
//!   form their own element block (4.1), blocks in region order, each tet keeping tag
//!   `t + 1`; in 2.2 each tet carries physical and elementary tag `k + 1`;
//! * the field is written as `$NodeData` named `f` (time 0, step 0, one component).
//!
//! ASCII coordinates and values use the shortest decimal form that parses back to the same
//! `f64`. Binary 4.1 holds the same sections, entities, blocks and tags as ASCII 4.1, in Gmsh's
//! binary encoding (little-endian, the `int` 1 after the format line): counts and node and
//! element tags as 8-byte `size_t`, entity, physical and type numbers and the node tags of
//! `$NodeData` as 4-byte `int`, coordinates and values as `f64`; `$PhysicalNames` and the
//! tags of `$NodeData` stay text (written by `msh_binary.rs`).

use std::io::{self, Write};

use super::msh_binary::write_v41_binary;
use super::source::{InMemory, MeshSource};
use super::write_common::{check_lengths, TextOut};
use crate::mesh::{BoundaryLabel, TetMesh};

/// Which `.msh` format version [`write_msh`] produces.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum MshVersion {
    /// Gmsh 4.1 ASCII (`$Entities`, entity-blocked `$Nodes`/`$Elements`); the default.
    #[default]
    V41,
    /// Legacy Gmsh 2.2 ASCII, read by most third-party tools.
    V22,
    /// Gmsh 4.1 binary: the content of [`MshVersion::V41`], smaller and faster to read.
    V41Binary,
}

/// Physical tag of the volume group `domain` (one interval).
pub const DOMAIN_PHYSICAL_TAG: u32 = 4;

/// Physical (and elementary surface) tag of the group of `label` in a run of `levels`
/// levels: its [`BoundaryLabel::code`] plus one (1, 2, 3 for alpha, beta, box).
pub fn label_tag(label: BoundaryLabel, levels: usize) -> u32 {
    label.code(levels) as u32 + 1
}

/// Gmsh element type of a 3-node triangle.
pub(super) const TRIANGLE: u32 = 2;
/// Gmsh element type of a 4-node tetrahedron.
pub(super) const TETRAHEDRON: u32 = 4;
/// Elementary tag of the single volume entity (one interval).
const VOLUME_ENTITY: u32 = 1;

/// A volume entity with its physical group: the whole mesh (one interval) or one region.
pub(super) struct Volume {
    /// Elementary and physical tag.
    pub(super) entity: u32,
    pub(super) physical: u32,
    pub(super) name: String,
    /// The region whose tets it holds; `None`: every tet.
    pub(super) region: Option<u8>,
    pub(super) tets: usize,
}

/// What a `.msh` file groups: the labels that occur and the volumes.
pub(super) struct Layout {
    pub(super) levels: usize,
    pub(super) present: Vec<(BoundaryLabel, usize)>,
    pub(super) volumes: Vec<Volume>,
}

impl Layout {
    fn of(src: &dyn MeshSource) -> Layout {
        let volumes = if src.region_count() == 0 {
            vec![Volume {
                entity: VOLUME_ENTITY,
                physical: DOMAIN_PHYSICAL_TAG,
                name: "domain".to_string(),
                region: None,
                tets: src.num_tets(),
            }]
        } else {
            let counts = src.region_tets().into_iter().enumerate();
            counts
                .filter(|&(_, n)| n > 0)
                .map(|(k, n)| Volume {
                    entity: k as u32 + 1,
                    physical: k as u32 + 1,
                    name: src.region_name(k),
                    region: Some(k as u8),
                    tets: n,
                })
                .collect()
        };
        Layout {
            levels: src.level_count(),
            present: src.present_labels(),
            volumes,
        }
    }

    pub(super) fn tag(&self, label: BoundaryLabel) -> u32 {
        label_tag(label, self.levels)
    }

    /// The entity the nodes are classified on: the first volume.
    pub(super) fn node_entity(&self) -> u32 {
        self.volumes.first().map_or(VOLUME_ENTITY, |v| v.entity)
    }

    /// Element blocks: one per volume, one per label that occurs.
    pub(super) fn blocks(&self) -> usize {
        self.volumes.len() + self.present.len()
    }
}

/// Visits the tets of volume `v` with their element tags (`t + 1`), in mesh order.
pub(super) fn volume_tets(
    src: &dyn MeshSource,
    v: &Volume,
    f: &mut dyn FnMut(usize, &[u32; 4]) -> io::Result<()>,
) -> io::Result<()> {
    let mut tag = 0usize;
    src.tets_in_regions(&mut |ts, rs| {
        for (i, tet) in ts.iter().enumerate() {
            tag += 1;
            if v.region.is_none_or(|k| rs[i] == k) {
                f(tag, tet)?;
            }
        }
        Ok(())
    })
}

/// Physical and elementary tag of a tet of region `region` (`None`: one interval) in 2.2.
fn tet_tags(region: Option<&u8>) -> (u32, u32) {
    match region {
        Some(&k) => (u32::from(k) + 1, u32::from(k) + 1),
        None => (DOMAIN_PHYSICAL_TAG, VOLUME_ENTITY),
    }
}

/// Writes `mesh` as a Gmsh mesh of the given version: nodes, tetrahedra (volume
/// physical group `domain`, or one per region), the labelled boundary triangles (surface
/// physical groups `alpha`, `beta`, `box`, or `level1`, … and `box` with the interfaces
/// between regions; only those that occur) and the nodal field `f` (see the module
/// documentation for numbering and tags). The output is deterministic.
///
/// # Errors
/// Returns the first error of `w`, or [`io::ErrorKind::InvalidInput`] when the mesh is
/// inconsistent (`values` or `boundary_labels` of the wrong length) or, in binary 4.1, has
/// more nodes than a 4-byte `int` numbers (the node tags of `$NodeData`).
pub fn write_msh(mesh: &TetMesh, w: &mut dyn Write, version: MshVersion) -> io::Result<()> {
    check_lengths(mesh)?;
    write_msh_source(&InMemory::new(mesh), w, version)
}

/// [`write_msh`] from any [`MeshSource`].
pub(crate) fn write_msh_source(
    src: &dyn MeshSource,
    w: &mut dyn Write,
    version: MshVersion,
) -> io::Result<()> {
    let layout = Layout::of(src);
    let write_text: TextWriter = match version {
        MshVersion::V41 => write_v41,
        MshVersion::V22 => write_v22,
        MshVersion::V41Binary => return write_v41_binary(src, &layout, w),
    };
    let mut out = TextOut::new(w);
    write_text(src, &layout, &mut out)?;
    out.finish()
}

/// An ASCII writer: mesh, its groups, output.
type TextWriter = fn(&dyn MeshSource, &Layout, &mut TextOut) -> io::Result<()>;

fn header(out: &mut TextOut, version: &str, layout: &Layout) -> io::Result<()> {
    out.s("$MeshFormat").nl()?;
    out.s(version).s(" 0 8").nl()?;
    out.s("$EndMeshFormat").nl()?;
    physical_names(out, layout)
}

/// `$PhysicalNames` (text in every version).
pub(super) fn physical_names(out: &mut TextOut, layout: &Layout) -> io::Result<()> {
    out.s("$PhysicalNames").nl()?;
    out.int(layout.present.len() + layout.volumes.len()).nl()?;
    for &(label, _) in &layout.present {
        out.s("2 ")
            .int(layout.tag(label))
            .s(" \"")
            .s(&label.name_in(layout.levels))
            .s("\"")
            .nl()?;
    }
    for v in &layout.volumes {
        out.s("3 ")
            .int(v.physical)
            .s(" \"")
            .s(&v.name)
            .s("\"")
            .nl()?;
    }
    out.s("$EndPhysicalNames").nl()
}

/// The text head of `$NodeData`: name `f`, time 0, step 0, one component, the node count.
pub(super) fn node_data_head(src: &dyn MeshSource, out: &mut TextOut) -> io::Result<()> {
    out.s("$NodeData").nl()?;
    out.s("1").nl()?;
    out.s("\"f\"").nl()?;
    out.s("1").nl()?;
    out.s("0").nl()?;
    out.s("3").nl()?;
    out.s("0").nl()?;
    out.s("1").nl()?;
    out.int(src.num_points()).nl()
}

fn node_data(src: &dyn MeshSource, out: &mut TextOut) -> io::Result<()> {
    node_data_head(src, out)?;
    let mut i = 0usize;
    src.values(&mut |vs| {
        for &v in vs {
            i += 1;
            out.int(i).s(" ").float(v).nl()?;
        }
        Ok(())
    })?;
    out.s("$EndNodeData").nl()
}

fn point<'o, 'w>(out: &'o mut TextOut<'w>, p: [f64; 3]) -> &'o mut TextOut<'w> {
    out.vec3(p)
}

/// The bounding box of [`MeshSource::bbox`], zeros if there are no points.
fn bbox(src: &dyn MeshSource, label: Option<BoundaryLabel>) -> [f64; 6] {
    let b = src.bbox(label);
    if b[0] > b[3] {
        [0.0; 6]
    } else {
        b
    }
}

fn write_v41(src: &dyn MeshSource, layout: &Layout, out: &mut TextOut) -> io::Result<()> {
    header(out, "4.1", layout)?;
    entities_v41(src, layout, out)?;
    nodes_v41(src, layout, out)?;
    elements_v41(src, layout, out)?;
    node_data(src, out)
}

/// An elementary entity of `$Entities` (4.1) with its one physical tag.
pub(super) struct Entity {
    pub(super) tag: u32,
    pub(super) bbox: [f64; 6],
    pub(super) physical: u32,
    /// Tags of the bounding entities (one dimension lower).
    pub(super) bounding: Vec<u32>,
}

/// The entities: one surface per label that occurs (bounded by no curves), then the volumes,
/// each bounded by the surfaces of its levels and the box (one interval: all surfaces).
pub(super) fn entity_list(src: &dyn MeshSource, layout: &Layout) -> Vec<Entity> {
    let mut list: Vec<Entity> = layout
        .present
        .iter()
        .map(|&(label, _)| Entity {
            tag: layout.tag(label),
            bbox: bbox(src, Some(label)),
            physical: layout.tag(label),
            bounding: Vec::new(),
        })
        .collect();
    for v in &layout.volumes {
        let bounds = |l: BoundaryLabel| match (v.region, l.level()) {
            (Some(k), Some(i)) => i == k as usize || i == k as usize + 1,
            _ => true,
        };
        let bounding = layout.present.iter().filter(|&&(l, _)| bounds(l));
        list.push(Entity {
            tag: v.entity,
            bbox: bbox(src, None),
            physical: v.physical,
            bounding: bounding.map(|&(l, _)| layout.tag(l)).collect(),
        });
    }
    list
}

/// The four numbers after `$Nodes` or `$Elements` (4.1): blocks, count, smallest and
/// largest tag (tags are `1..=count`; `0 0` when empty, as gmsh writes empty meshes).
pub(super) fn section_counts(blocks: usize, count: usize) -> [usize; 4] {
    [blocks, count, usize::from(count > 0), count]
}

/// `$Entities`: one surface per label that occurs, then the volume entities.
fn entities_v41(src: &dyn MeshSource, layout: &Layout, out: &mut TextOut) -> io::Result<()> {
    out.s("$Entities").nl()?;
    out.s("0 0 ")
        .int(layout.present.len())
        .s(" ")
        .int(layout.volumes.len())
        .nl()?;
    for e in entity_list(src, layout) {
        out.int(e.tag);
        bbox_fields(out, e.bbox);
        out.s(" 1 ").int(e.physical).s(" ").int(e.bounding.len());
        for b in e.bounding {
            out.s(" ").int(b);
        }
        out.nl()?;
    }
    out.s("$EndEntities").nl()
}

/// Appends four numbers separated by spaces and ends the line.
fn counts_line(out: &mut TextOut, c: [usize; 4]) -> io::Result<()> {
    out.int(c[0])
        .s(" ")
        .int(c[1])
        .s(" ")
        .int(c[2])
        .s(" ")
        .int(c[3])
        .nl()
}

/// Appends the six numbers of a bounding box, each preceded by a space.
fn bbox_fields(out: &mut TextOut, b: [f64; 6]) {
    for x in b {
        out.s(" ").float(x);
    }
}

/// `$Nodes`: all nodes in one block classified on the first volume entity.
fn nodes_v41(src: &dyn MeshSource, layout: &Layout, out: &mut TextOut) -> io::Result<()> {
    let n_points = src.num_points();
    out.s("$Nodes").nl()?;
    counts_line(out, section_counts(1, n_points))?;
    out.s("3 ")
        .int(layout.node_entity())
        .s(" 0 ")
        .int(n_points)
        .nl()?;
    for i in 1..=n_points {
        out.int(i).nl()?;
    }
    src.points(&mut |ps| {
        for &p in ps {
            point(out, p).nl()?;
        }
        Ok(())
    })?;
    out.s("$EndNodes").nl()
}

/// `$Elements`: the tets in one block per volume entity, then one triangle block per label
/// that occurs.
fn elements_v41(src: &dyn MeshSource, layout: &Layout, out: &mut TextOut) -> io::Result<()> {
    let n_tets = src.num_tets();
    let n_elems = n_tets + src.num_triangles();
    out.s("$Elements").nl()?;
    counts_line(out, section_counts(layout.blocks(), n_elems))?;
    for v in &layout.volumes {
        element_block(out, v.entity, 3, TETRAHEDRON, v.tets)?;
        volume_tets(src, v, &mut |tag, tet| element_nodes(out.int(tag), tet))?;
    }
    let mut tag = n_tets;
    for &(label, count) in &layout.present {
        element_block(out, layout.tag(label), 2, TRIANGLE, count)?;
        src.triangles(label, &mut |ts| {
            for tri in ts {
                tag += 1;
                element_nodes(out.int(tag), tri)?;
            }
            Ok(())
        })?;
    }
    out.s("$EndElements").nl()
}

/// The header line of an element block: entity dimension, entity tag, element type, count.
fn element_block(
    out: &mut TextOut,
    entity: u32,
    dim: u32,
    element_type: u32,
    count: usize,
) -> io::Result<()> {
    out.int(dim)
        .s(" ")
        .int(entity)
        .s(" ")
        .int(element_type)
        .s(" ")
        .int(count)
        .nl()
}

/// Appends the 1-based node tags of an element, each preceded by a space, and ends the line.
fn element_nodes(out: &mut TextOut, nodes: &[u32]) -> io::Result<()> {
    for &v in nodes {
        out.s(" ").int(v + 1);
    }
    out.nl()
}

fn write_v22(src: &dyn MeshSource, layout: &Layout, out: &mut TextOut) -> io::Result<()> {
    header(out, "2.2", layout)?;
    out.s("$Nodes").nl()?;
    out.int(src.num_points()).nl()?;
    let mut i = 0usize;
    src.points(&mut |ps| {
        for &p in ps {
            i += 1;
            out.int(i).s(" ");
            point(out, p).nl()?;
        }
        Ok(())
    })?;
    out.s("$EndNodes").nl()?;
    elements_v22(src, layout, out)?;
    node_data(src, out)
}

/// `$Elements` (2.2): the tets, then the labelled triangles grouped by label; each element
/// carries two tags, physical and elementary.
fn elements_v22(src: &dyn MeshSource, layout: &Layout, out: &mut TextOut) -> io::Result<()> {
    out.s("$Elements").nl()?;
    out.int(src.num_tets() + src.num_triangles()).nl()?;
    let mut tag = 0usize;
    src.tets_in_regions(&mut |ts, rs| {
        for (i, tet) in ts.iter().enumerate() {
            tag += 1;
            let (physical, entity) = tet_tags(rs.get(i));
            out.int(tag).s(" 4 2 ").int(physical).s(" ").int(entity);
            element_nodes(out, tet)?;
        }
        Ok(())
    })?;
    for &(label, _) in &layout.present {
        let lt = layout.tag(label);
        src.triangles(label, &mut |ts| {
            for tri in ts {
                tag += 1;
                out.int(tag).s(" 2 2 ").int(lt).s(" ").int(lt);
                element_nodes(out, tri)?;
            }
            Ok(())
        })?;
    }
    out.s("$EndElements").nl()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::source::{Visit, VisitRegions};

    /// A [`MeshSource`] that hands every list on in slices of at most two items, as a mesh
    /// read back from spill files is.
    struct InTwos<'a>(InMemory<'a>);

    fn in_twos<T>(all: &[T], f: Visit<T>) -> io::Result<()> {
        all.chunks(2).try_for_each(f)
    }

    impl MeshSource for InTwos<'_> {
        fn num_points(&self) -> usize {
            self.0.num_points()
        }
        fn num_tets(&self) -> usize {
            self.0.num_tets()
        }
        fn level_count(&self) -> usize {
            self.0.level_count()
        }
        fn region_name(&self, k: usize) -> String {
            self.0.region_name(k)
        }
        fn regions(&self, f: Visit<u8>) -> io::Result<()> {
            self.0.regions(&mut |all| in_twos(all, f))
        }
        fn region_tets(&self) -> Vec<usize> {
            self.0.region_tets()
        }
        fn tets_in_regions(&self, f: VisitRegions) -> io::Result<()> {
            self.0.tets_in_regions(&mut |ts, rs| {
                let rs = |i: usize| rs.get(2 * i..(2 * i + 2).min(rs.len())).unwrap_or(&[]);
                ts.chunks(2).enumerate().try_for_each(|(i, t)| f(t, rs(i)))
            })
        }
        fn label_counts(&self) -> [usize; crate::mesh::NUM_LABELS] {
            self.0.label_counts()
        }
        fn bbox(&self, label: Option<BoundaryLabel>) -> [f64; 6] {
            self.0.bbox(label)
        }
        fn points(&self, f: Visit<[f64; 3]>) -> io::Result<()> {
            self.0.points(&mut |all| in_twos(all, f))
        }
        fn values(&self, f: Visit<f64>) -> io::Result<()> {
            self.0.values(&mut |all| in_twos(all, f))
        }
        fn tets(&self, f: Visit<[u32; 4]>) -> io::Result<()> {
            self.0.tets(&mut |all| in_twos(all, f))
        }
        fn triangles(&self, label: BoundaryLabel, f: Visit<[u32; 3]>) -> io::Result<()> {
            self.0.triangles(label, &mut |all| in_twos(all, f))
        }
        fn faces(&self, label: BoundaryLabel, above: bool, f: Visit<(u32, u8)>) -> io::Result<()> {
            self.0.faces(label, above, f)
        }
    }

    /// Two tets on a shared face; three boundary triangles labelled alpha, box, box.
    fn two_tets() -> TetMesh {
        TetMesh {
            regions: Default::default(),
            points: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [1.0, 1.0, 1.5],
            ],
            values: vec![0.5, 1.0, 1.5, 2.0, -0.25],
            tets: vec![[0, 1, 2, 3], [1, 2, 3, 4]],
            boundary: vec![[0, 2, 1], [1, 2, 4], [0, 1, 3]],
            boundary_labels: vec![BoundaryLabel::ALPHA, BoundaryLabel::Box, BoundaryLabel::Box],
        }
    }

    /// Three tets in regions 1, 0, 1 (of three levels), the faces between them interfaces.
    fn three_tets_in_two_regions() -> TetMesh {
        let mut m = two_tets();
        m.points.push([-1.0, -1.0, -1.0]);
        m.values.push(0.0);
        m.tets.insert(0, [0, 2, 1, 5]);
        m.boundary = vec![[1, 2, 4]];
        m.boundary_labels = vec![BoundaryLabel::Box];
        m.regions = crate::mesh::Regions {
            levels: 3,
            tets: vec![1, 0, 1],
            boundary: vec![1],
            interfaces: vec![[0, 2, 1], [1, 2, 3]],
            interface_labels: vec![BoundaryLabel::Level(1); 2],
            names: vec!["inner".into()],
        };
        m
    }

    #[test]
    fn slices_of_any_size_give_the_same_bytes() {
        for mesh in [two_tets(), three_tets_in_two_regions()] {
            for version in [MshVersion::V41, MshVersion::V22, MshVersion::V41Binary] {
                let mut whole = Vec::new();
                write_msh(&mesh, &mut whole, version).unwrap();
                let mut sliced = Vec::new();
                write_msh_source(&InTwos(InMemory::new(&mesh)), &mut sliced, version).unwrap();
                assert_eq!(whole, sliced, "{version:?}");
            }
        }
    }

    #[test]
    fn regions_are_volumes_with_their_tets_in_blocks() {
        let mut out = Vec::new();
        write_msh(&three_tets_in_two_regions(), &mut out, MshVersion::V41).unwrap();
        let text = String::from_utf8(out).unwrap();
        let names = "$PhysicalNames\n4\n2 2 \"level2\"\n2 4 \"box\"\n3 1 \"inner\"\n\
                     3 2 \"region2\"\n$EndPhysicalNames\n";
        assert!(text.contains(names), "{text}");
        // 3 tets in 2 blocks (tags 2; 1 and 3), 2 interface triangles, 1 on the box
        let elements = "$Elements\n4 6 1 6\n3 1 4 1\n2 1 2 3 4\n3 2 4 2\n1 1 3 2 6\n\
                        3 2 3 4 5\n2 2 2 2\n4 1 3 2\n5 2 3 4\n2 4 2 1\n6 2 3 5\n$EndElements\n";
        assert!(text.contains(elements), "{text}");
    }

    #[test]
    fn binary_holds_the_numbers_of_the_ascii_file() {
        let mesh = two_tets();
        let mut b = Vec::new();
        write_msh(&mesh, &mut b, MshVersion::V41Binary).unwrap();
        // 8-byte counts and tags (N), 4-byte ints (I), 8-byte doubles (D)
        const N: usize = 8;
        const I: usize = 4;
        const D: usize = 8;
        // section head: 4 counts; block head: dimension, entity, type or flag, count
        let (head, block) = (4 * N, 3 * I + N);
        // entity: tag, box, 1 physical tag, bounding tags (2 for the volume, 0 for surfaces)
        let entities = 4 * N + 3 * (I + 6 * D + N + I + N) + 2 * I;
        let nodes = head + block + 5 * (N + 3 * D);
        // 2 tets, 3 triangles (1 alpha, 2 box) in 3 blocks; an element is its tag and nodes
        let elements = head + 3 * block + 2 * 5 * N + 3 * 4 * N;
        let node_data = 5 * (I + D);
        let text = "$MeshFormat\n4.1 1 8\n\n$EndMeshFormat\n$PhysicalNames\n3\n\
                    2 1 \"alpha\"\n2 3 \"box\"\n3 4 \"domain\"\n$EndPhysicalNames\n\
                    $Entities\n\n$EndEntities\n$Nodes\n\n$EndNodes\n$Elements\n\n$EndElements\n\
                    $NodeData\n1\n\"f\"\n1\n0\n3\n0\n1\n5\n\n$EndNodeData\n";
        let data = I + entities + nodes + elements + node_data;
        assert_eq!(b.len(), text.len() + data);
    }
}
