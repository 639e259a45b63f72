//! What of the side panel a person can read, from egui's layout of one frame: the widgets that no
//! scrolling brings whole into view (cut at the panel's sides, or below the window outside the
//! scroll area) and the lines of text shown whole. The window saves it beside a screenshot
//! (`.panel.txt`), where the window test reads it.

use egui::epaint::ClippedShape;
use egui::{Rect, Shape, WidgetRect};

/// Slack for rounding in egui's layout, in points.
const SLACK: f32 = 0.5;

/// The part of the panel that scrolls (up and down only).
pub struct Scrolling {
    /// Where it shows its content.
    pub view: Rect,
    /// Where all of its content lies, shown or scrolled out of view.
    pub content: Rect,
}

impl Scrolling {
    /// Whether scrolling brings `rect` whole into view: within the content's height and the
    /// view's width, the view itself within `panel`.
    fn reaches(&self, panel: Rect, rect: Rect) -> bool {
        let reachable = Rect::from_x_y_ranges(self.view.x_range(), self.content.y_range());
        within(panel, self.view) && within(reachable, rect)
    }
}

/// `inner` lies in `outer`, give or take egui's rounding.
fn within(outer: Rect, inner: Rect) -> bool {
    outer.expand(SLACK).contains_rect(inner)
}

pub struct Legibility {
    /// The panel, in points.
    pub panel: Rect,
    /// Widgets (and rows of widgets) that are not whole within the panel, and that scrolling does
    /// not bring whole into view.
    pub unreachable: Vec<Rect>,
    /// Text drawn whole within its clip and the panel, one entry a text.
    pub shown: Vec<String>,
}

impl Legibility {
    /// `widgets`: those the panel's contents made; `scrolling`: its scrolling part; `shapes`: the
    /// frame's.
    pub fn of(
        panel: Rect,
        scrolling: Option<&Scrolling>,
        widgets: &[WidgetRect],
        shapes: &[ClippedShape],
    ) -> Self {
        let unreachable = widgets
            .iter()
            .map(|w| w.rect)
            .filter(|&r| !(within(panel, r) || scrolling.is_some_and(|s| s.reaches(panel, r))))
            .collect();
        let mut shown = Vec::new();
        for clipped in shapes {
            collect_shown(
                &clipped.shape,
                clipped.clip_rect.intersect(panel),
                &mut shown,
            );
        }
        Self {
            panel,
            unreachable,
            shown,
        }
    }

    /// One line each: `panel` with its rect, `unreachable` with each widget's, `shown` with each
    /// text (its lines joined by spaces).
    pub fn report(&self) -> String {
        let rect = |r: Rect| format!("{} {} {} {}", r.min.x, r.min.y, r.max.x, r.max.y);
        let mut lines = vec![format!("panel {}", rect(self.panel))];
        lines.extend(
            self.unreachable
                .iter()
                .map(|&r| format!("unreachable {}", rect(r))),
        );
        lines.extend(
            self.shown
                .iter()
                .map(|t| format!("shown {}", t.replace('\n', " "))),
        );
        lines.join("\n") + "\n"
    }
}

/// The texts of `shape` drawn whole within `visible`.
fn collect_shown(shape: &Shape, visible: Rect, shown: &mut Vec<String>) {
    match shape {
        Shape::Text(text) if within(visible, text.visual_bounding_rect()) => {
            shown.push(text.galley.text().to_string())
        }
        Shape::Vec(shapes) => {
            for s in shapes {
                collect_shown(s, visible, shown);
            }
        }
        _ => {}
    }
}
