//! The viewer's default layout for a recording: a rerun *blueprint*, written as the blueprint
//! archetypes themselves (as rerun's Python SDK writes them). rerun's Rust builder
//! (`rerun::blueprint`) cannot set what a robot recording needs: a 3D camera that follows the
//! robot (`EyeControls3D`) and per-entity history for trails (`VisibleTimeRanges`).
//!
//! The blueprint is sent as the application's active and default layout: the viewer shows it
//! when it opens the file, and "reset blueprint" returns to it after the user has rearranged the
//! views.

use anyhow::Result;
use rerun::RecordingStream;
use rerun::datatypes::{TimeInt, TimeRange, TimeRangeBoundary, VisibleTimeRange};
use rerun::external::re_log_types::{BlueprintActivationCommand, LogMsg};
use rerun::external::re_sdk_types::blueprint::archetypes::{
    ContainerBlueprint, EyeControls3D, PanelBlueprint, PlotLegend, TimeAxis, TimePanelBlueprint,
    ViewBlueprint, ViewContents, ViewportBlueprint, VisibleTimeRanges,
};
use rerun::external::re_sdk_types::blueprint::components::{
    AutoLayout, AutoViews, ColumnShare, ContainerKind, Corner2D, IncludedContent, LinkAxis,
    PanelState, QueryExpression, RootContainer, RowShare, TimelineName, ViewClass,
};

/// A view or a container of views.
pub enum Layout {
    Container(Container),
    View(View),
}

/// Views side by side, one above the other, or in tabs.
pub struct Container {
    kind: ContainerKind,
    name: Option<String>,
    children: Vec<Layout>,
    /// Width (horizontal) or height (vertical) shares of the children; empty for equal shares.
    shares: Vec<f32>,
}

impl Layout {
    fn container(kind: ContainerKind, children: Vec<Layout>, shares: Vec<f32>) -> Self {
        Layout::Container(Container {
            kind,
            name: None,
            children,
            shares,
        })
    }

    /// Side by side, with the given width shares (empty: equal).
    pub fn horizontal(children: Vec<Layout>, shares: Vec<f32>) -> Self {
        Layout::container(ContainerKind::Horizontal, children, shares)
    }

    /// One above the other, with the given height shares (empty: equal).
    pub fn vertical(children: Vec<Layout>, shares: Vec<f32>) -> Self {
        Layout::container(ContainerKind::Vertical, children, shares)
    }

    /// Tabs, the first one shown.
    pub fn tabs(children: Vec<Layout>) -> Self {
        Layout::container(ContainerKind::Tabs, children, Vec::new())
    }

    /// A plot's title from its entity's name — words, and the unit of what it plots (every plot
    /// hexsim records is listed; another keeps its name) — and whether it draws several series
    /// (a legend then names them; a lone series is named by the title).
    pub fn plot_title(entity: &str) -> (String, bool) {
        let (title, series) = match entity {
            "height_above_ground" => ("body height above the ground (m)", false),
            "attitude_deg" => ("body attitude (°)", true),
            "forward_speed" => ("forward speed (m/s)", false),
            "normal_force" => ("normal force (N)", true),
            "slip_speed" => ("slip speed (m/s)", true),
            "angle" => ("joint angles and targets (rad)", true),
            "torque" => ("joint torques (N·m)", true),
            "energy" => ("energy (J)", true),
            "height" => ("height (m)", false),
            "force" => ("force (N)", true),
            "penetration_mm" => ("penetration (mm)", false),
            "speed" => ("speed (m/s)", false),
            // a comparison's plots: one series per setting
            "total_energy" => ("total energy (J)", true),
            "slip" => ("slip speed (m/s)", true),
            "forward_x" => ("forward position x (m)", true),
            "body_z" => ("body height above the ground (m)", true),
            "roll_deg" => ("roll (°)", true),
            "pitch_deg" => ("pitch (°)", true),
            "feet_normal_force" => ("feet's normal forces, summed (N)", true),
            "feet_slip" => ("feet's slip speeds, summed (m/s)", true),
            other => (other, true),
        };
        (title.to_string(), series)
    }

    /// A tab named `name` of time-series views stacked one above the other, one per entity in
    /// `origins`, each titled by what the entity's last name plots, with its unit
    /// ([`Self::plot_title`]).
    pub fn plots(name: &str, origins: &[&str]) -> Self {
        Layout::vertical(
            origins
                .iter()
                .map(|o| {
                    let (title, series) = Self::plot_title(o.rsplit('/').next().unwrap_or(o));
                    let view = View::time_series(&title, o);
                    if series { view } else { view.without_legend() }.into()
                })
                .collect(),
            Vec::new(),
        )
        .named(name)
    }

    /// Names a container (a tab's title); a view keeps its own name.
    pub fn named(mut self, name: &str) -> Self {
        if let Layout::Container(c) = &mut self {
            c.name = Some(name.to_string());
        }
        self
    }
}

/// What a view shows and how.
pub struct View {
    class: &'static str,
    name: String,
    origin: String,
    contents: Vec<String>,
    /// The 3D camera follows this entity (a `Pinhole` camera: the view looks through it).
    camera: Option<String>,
    /// Entities drawn with their history (trails) instead of their latest value only.
    history: Vec<(String, History)>,
    /// A time series' legend (in the top-right corner, the least crowded by curves that start
    /// at a settled value); hidden for a lone series, which the title names.
    legend: bool,
}

/// How much of an entity's past a 3D view draws.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum History {
    /// Everything logged up to the time cursor (a path).
    Whole,
    /// The last so many seconds before the time cursor (a trail that fades out of view).
    Last(f64),
}

impl View {
    fn new(class: &'static str, name: &str, origin: &str) -> Self {
        View {
            class,
            name: name.to_string(),
            origin: origin.to_string(),
            contents: vec!["$origin/**".into()],
            camera: None,
            history: Vec::new(),
            legend: true,
        }
    }

    /// A time series without its legend.
    pub fn without_legend(mut self) -> Self {
        self.legend = false;
        self
    }

    /// A 3D view of everything under `origin`.
    pub fn spatial_3d(name: &str, origin: &str) -> Self {
        View::new("3D", name, origin)
    }

    /// Time series of the scalars under `origin`.
    pub fn time_series(name: &str, origin: &str) -> Self {
        View::new("TimeSeries", name, origin)
    }

    /// Lanes of discrete states (`StateChange`) over time, one per entity under `origin`.
    pub fn state_timeline(name: &str, origin: &str) -> Self {
        View::new("StateTimeline", name, origin)
    }

    /// A text document (`TextDocument`) logged at `origin`.
    pub fn text_document(name: &str, origin: &str) -> Self {
        View::new("TextDocument", name, origin)
    }

    /// The 3D view looks through the `Pinhole` camera logged at `entity` (until the user moves
    /// the view, which leaves the camera where it is).
    pub fn through_camera(mut self, entity: &str) -> Self {
        self.camera = Some(entity.to_string());
        self
    }

    /// Draws `entity` with its history on the time panel's timeline.
    pub fn with_history(mut self, entity: &str, history: History) -> Self {
        self.history.push((entity.to_string(), history));
        self
    }
}

impl From<View> for Layout {
    fn from(view: View) -> Self {
        Layout::View(view)
    }
}

/// Ids of views and containers: counted, so the same layout gives the same blueprint.
struct Ids(u64);

impl Ids {
    fn next(&mut self) -> u64 {
        self.0 += 1;
        self.0
    }
}

/// The UUID the viewer knows an id by: a version-4-shaped UUID whose last field is the id.
fn uuid(id: u64) -> String {
    format!("00000000-0000-4000-8000-{id:012x}")
}

/// The same UUID's bytes.
fn uuid_bytes(id: u64) -> [u8; 16] {
    (0x4000_8000_0000_0000_0000_u128 | u128::from(id)).to_be_bytes()
}

/// Sends `root` as the default blueprint of `stream`'s application, with the time panel on
/// `timeline` (a duration timeline, whose history ranges are in seconds), or on none for a still
/// picture (whose views then cannot draw histories).
pub fn send(stream: &RecordingStream, root: &Layout, timeline: Option<&str>) -> Result<()> {
    let application = stream
        .store_info()
        .map(|info| info.application_id().clone())
        .ok_or_else(|| anyhow::anyhow!("the recording has no application id"))?;
    let (blueprint, storage) = rerun::RecordingStreamBuilder::new(application)
        .blueprint()
        .memory()?;
    // the viewer identifies blueprint data by this timeline
    blueprint.set_time_sequence("blueprint", 0);
    let mut ids = Ids(0);
    let (_, root_id) = log_layout(&blueprint, root, timeline, &mut ids)?;
    blueprint.log(
        "viewport",
        &ViewportBlueprint::new()
            .with_root_container(RootContainer(uuid_bytes(root_id).into()))
            .with_auto_layout(AutoLayout(false.into()))
            .with_auto_views(AutoViews(false.into())),
    )?;
    // the views get the whole window; the side panels and the time panel's stream tree are a
    // click away
    let mut time_panel = TimePanelBlueprint::new().with_state(PanelState::Collapsed);
    if let Some(timeline) = timeline {
        time_panel = time_panel.with_timeline(TimelineName(timeline.into()));
    }
    blueprint.log("time_panel", &time_panel)?;
    for panel in ["blueprint_panel", "selection_panel"] {
        blueprint.log(
            panel,
            &PanelBlueprint::new().with_state(PanelState::Collapsed),
        )?;
    }
    let messages: Vec<LogMsg> = storage.take();
    let blueprint_id = messages
        .iter()
        .find_map(|m| match m {
            LogMsg::SetStoreInfo(info) => Some(info.info.store_id.clone()),
            _ => None,
        })
        .ok_or_else(|| anyhow::anyhow!("the blueprint stream wrote no store info"))?;
    // Active as well as default. A default alone is only a fallback: the native viewer restores
    // the layout it saved for "hexsim" last time, and any viewer that draws a frame between the
    // recording's first messages and this command builds an automatic layout, which the default
    // then never replaces (seen as nine small views on the `step` timeline).
    stream.send_blueprint(
        messages,
        BlueprintActivationCommand {
            blueprint_id,
            make_active: true,
            make_default: true,
        },
    );
    Ok(())
}

/// Logs a view or container and everything in it; returns its blueprint path and id.
fn log_layout(
    stream: &RecordingStream,
    layout: &Layout,
    timeline: Option<&str>,
    ids: &mut Ids,
) -> Result<(String, u64)> {
    let c = match layout {
        Layout::View(view) => return log_view(stream, view, timeline, ids),
        Layout::Container(c) => c,
    };
    let id = ids.next();
    let path = format!("container/{}", uuid(id));
    let mut contents = Vec::new();
    for child in &c.children {
        let (child_path, _) = log_layout(stream, child, timeline, ids)?;
        contents.push(IncludedContent(child_path.into()));
    }
    let mut container = ContainerBlueprint::new(c.kind).with_contents(contents);
    if let Some(name) = &c.name {
        container = container.with_display_name(name.as_str());
    }
    if !c.shares.is_empty() {
        match c.kind {
            ContainerKind::Horizontal => {
                container =
                    container.with_col_shares(c.shares.iter().map(|&x| ColumnShare(x.into())));
            }
            ContainerKind::Vertical => {
                container = container.with_row_shares(c.shares.iter().map(|&x| RowShare(x.into())));
            }
            _ => {}
        }
    }
    stream.log(path.as_str(), &container)?;
    Ok((path, id))
}

fn log_view(
    stream: &RecordingStream,
    view: &View,
    timeline: Option<&str>,
    ids: &mut Ids,
) -> Result<(String, u64)> {
    let id = ids.next();
    let path = format!("view/{}", uuid(id));
    stream.log(
        format!("{path}/ViewContents"),
        &ViewContents::new(
            view.contents
                .iter()
                .map(|q| QueryExpression(q.clone().into())),
        ),
    )?;
    stream.log(
        path.as_str(),
        &ViewBlueprint::new(ViewClass(view.class.into()))
            .with_display_name(view.name.as_str())
            .with_space_origin(view.origin.as_str()),
    )?;
    if view.class == "TimeSeries" {
        stream.log(
            format!("{path}/PlotLegend"),
            &PlotLegend::new()
                .with_corner(Corner2D::RightTop)
                .with_visible(view.legend),
        )?;
    }
    if matches!(view.class, "TimeSeries" | "StateTimeline") {
        // plots share their time axis: zooming one zooms all, the footfall diagram included
        stream.log(
            format!("{path}/TimeAxis"),
            &TimeAxis::new().with_link(LinkAxis::LinkToGlobal),
        )?;
    }
    if let Some(camera) = &view.camera {
        stream.log(
            format!("{path}/EyeControls3D"),
            &EyeControls3D::new().with_tracking_entity(camera.as_str()),
        )?;
    }
    for (entity, history) in &view.history {
        let Some(timeline) = timeline else {
            anyhow::bail!("view {}: a history needs a timeline", view.name);
        };
        let start = match history {
            History::Whole => TimeRangeBoundary::Infinite,
            History::Last(seconds) => {
                TimeRangeBoundary::CursorRelative(TimeInt(-(seconds * 1e9).round() as i64))
            }
        };
        let range = VisibleTimeRange {
            timeline: timeline.into(),
            range: TimeRange {
                start,
                end: TimeRangeBoundary::AT_CURSOR,
            },
        };
        // where the Python SDK puts an entity's overrides: ViewContents/overrides/ENTITY/visualizers
        let entity = entity.trim_start_matches('/');
        stream.log(
            format!("{path}/ViewContents/overrides/{entity}/visualizers"),
            &VisibleTimeRanges::new([range]),
        )?;
    }
    Ok((path, id))
}
