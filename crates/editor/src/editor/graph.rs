//! The node graph: the tree drawn as boxes wired from each child into its parent, leaves
//! on the left and the root on the right — data flowing towards the output, as Gaea and
//! World Machine lay out theirs. It is drawn from the same scene as the outline every
//! frame, so the two never disagree; a click on a named node selects it, as in the
//! outline. `defs` are drawn above the tree, each its own small graph.

use egui::{Color32, Pos2, Rect, RichText, Stroke, Ui, Vec2, epaint::CubicBezierShape};

use crate::scene::{NodeSpec, Scene};

/// Size of a node's box, points.
const NODE: Vec2 = Vec2::new(130.0, 24.0);
/// Distance between columns and between rows, points (a node's kind is written in the
/// gap above its box).
const STEP: Vec2 = Vec2::new(160.0, 40.0);

/// One node of the laid-out graph.
#[derive(Clone, Debug, PartialEq)]
pub struct Placed<'a> {
    /// The node.
    pub node: &'a NodeSpec,
    /// Column, 0 the leftmost: the root of each graph is in the last column.
    pub column: usize,
    /// Row, from the top: leaves take consecutive rows, a parent the middle of its
    /// children's.
    pub row: f32,
    /// Index of the parent in [`Layout::nodes`], `None` for a root.
    pub parent: Option<usize>,
}

/// The layout of a scene's graphs: the `defs` first, then the tree.
#[derive(Clone, Debug, Default)]
pub struct Layout<'a> {
    /// The nodes, each graph in depth-first order.
    pub nodes: Vec<Placed<'a>>,
}

impl<'a> Layout<'a> {
    /// Lays out `scene`: columns by depth below the root (the roots rightmost, the deepest leaf leftmost), rows by
    /// leaves in the tree's order, a blank row between graphs.
    pub fn of(scene: &'a Scene) -> Self {
        let mut layout = Layout::default();
        let mut next_row = 0.0;
        for root in scene.defs.iter().chain([&scene.root]) {
            layout.place(root, None, 0, &mut next_row);
            next_row += 1.0;
        }
        // `place` left each node's depth in `column`: the deepest leaf goes leftmost.
        let deepest = layout.nodes.iter().map(|n| n.column).max().unwrap_or(0);
        for n in &mut layout.nodes {
            n.column = deepest - n.column;
        }
        layout
    }

    /// Places `node` (at `depth` below its root, kept in its `column` until
    /// [`Layout::of`] turns depths into columns) and its subtree; returns its row.
    fn place(
        &mut self,
        node: &'a NodeSpec,
        parent: Option<usize>,
        depth: usize,
        next_row: &mut f32,
    ) -> f32 {
        let at = self.nodes.len();
        self.nodes.push(Placed {
            node,
            column: depth,
            row: 0.0,
            parent,
        });
        let children = node.children();
        let row = if children.is_empty() {
            *next_row += 1.0;
            *next_row - 1.0
        } else {
            let rows: Vec<f32> = children
                .into_iter()
                .map(|c| self.place(c, Some(at), depth + 1, next_row))
                .collect();
            0.5 * (rows[0] + rows[rows.len() - 1])
        };
        self.nodes[at].row = row;
        row
    }

    /// The box of node `k`, in the graph's frame (points from its top-left corner).
    pub fn rect(&self, k: usize) -> Rect {
        let n = &self.nodes[k];
        Rect::from_min_size(Pos2::new(n.column as f32 * STEP.x, n.row * STEP.y), NODE)
    }
}

/// Shows the graph of `scene`; a click on a named node sets `selected` to its name.
pub fn show(ui: &mut Ui, scene: &Scene, selected: &mut Option<String>) {
    let layout = Layout::of(scene);
    egui::ScrollArea::both()
        .stick_to_right(true)
        .show(ui, |ui| {
            let size = (0..layout.nodes.len())
                .map(|k| layout.rect(k).max.to_vec2())
                .fold(Vec2::ZERO, Vec2::max);
            // Room above the first row for its kinds.
            let margin = Vec2::new(4.0, 14.0);
            let (area, _) = ui.allocate_exact_size(size + 2.0 * margin, egui::Sense::hover());
            let origin = area.min.to_vec2() + margin;
            let wire = Stroke::new(1.5, ui.visuals().weak_text_color());
            for (k, n) in layout.nodes.iter().enumerate() {
                let Some(p) = n.parent else { continue };
                let (from, to) = (layout.rect(k), layout.rect(p));
                let a = from.right_center() + origin;
                let b = to.left_center() + origin;
                let bend = Vec2::new(0.5 * (b.x - a.x), 0.0);
                ui.painter().add(CubicBezierShape::from_points_stroke(
                    [a, a + bend, b - bend, b],
                    false,
                    Color32::TRANSPARENT,
                    wire,
                ));
            }
            let small = egui::TextStyle::Small.resolve(ui.style());
            let weak = ui.visuals().weak_text_color();
            for (k, n) in layout.nodes.iter().enumerate() {
                let rect = layout.rect(k).translate(origin);
                let kind = n.node.kind();
                ui.painter().text(
                    rect.left_top() + Vec2::new(2.0, -1.0),
                    egui::Align2::LEFT_BOTTOM,
                    kind,
                    small.clone(),
                    weak,
                );
                match n.node.name() {
                    Some(name) => {
                        let on = selected.as_deref() == Some(name);
                        if ui.put(rect, egui::Button::selectable(on, name)).clicked() {
                            *selected = Some(name.to_string());
                        }
                    }
                    None => {
                        let frame = ui.visuals().widgets.noninteractive;
                        ui.painter().rect_stroke(
                            rect,
                            4.0,
                            frame.bg_stroke,
                            egui::StrokeKind::Inside,
                        );
                        ui.put(rect, egui::Label::new(RichText::new("(unnamed)").weak()))
                            .on_hover_text("name a node in the file to edit it here");
                    }
                }
            }
        });
}

#[cfg(test)]
mod tests {
    use super::*;

    const TREE: &str = r#"(
        version: 1,
        defs: [Primitive(name: "rock", shape: Sphere(center: (0, 0, 0), radius: 5), falloff: 2)],
        root: Difference(
            name: "all",
            base: Union(name: "hills", children: [
                Primitive(name: "a", shape: Sphere(center: (0, 0, 0), radius: 10), falloff: 2),
                Primitive(shape: Sphere(center: (30, 0, 0), radius: 10), falloff: 2),
            ]),
            carves: [Primitive(name: "hole", shape: Sphere(center: (0, 0, 5), radius: 4), falloff: 2)],
        ),
    )"#;

    #[test]
    fn parents_sit_right_of_their_children_amid_them_and_no_boxes_overlap() {
        let scene = crate::scene::parse_scene(TREE, std::path::Path::new("t.ron")).unwrap();
        let l = Layout::of(&scene);
        let names: Vec<_> = l.nodes.iter().map(|n| n.node.name()).collect();
        assert_eq!(
            names,
            [
                Some("rock"),
                Some("all"),
                Some("hills"),
                Some("a"),
                None,
                Some("hole")
            ]
        );
        for (k, n) in l.nodes.iter().enumerate() {
            let kids: Vec<&Placed> = l.nodes.iter().filter(|c| c.parent == Some(k)).collect();
            assert_eq!(kids.len(), n.node.children().len());
            for c in &kids {
                assert_eq!(c.column + 1, n.column, "{:?}", n.node.name());
            }
            if let (Some(first), Some(last)) = (kids.first(), kids.last()) {
                assert!(first.row <= n.row && n.row <= last.row);
            }
            for j in 0..k {
                assert!(!l.rect(j).intersects(l.rect(k)), "{j} and {k} overlap");
            }
        }
        // The roots in the last column; the def's graph above the tree's.
        assert_eq!(l.nodes[0].column, l.nodes[1].column);
        assert!(
            l.nodes[0].row
                < l.nodes
                    .iter()
                    .skip(1)
                    .map(|n| n.row)
                    .fold(f32::MAX, f32::min)
        );
    }
}
