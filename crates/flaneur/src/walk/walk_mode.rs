//! The walk modes by name: what the CLI's `--mode` spells, the window's keys switch
//! between and a live session falls back along. Each name stands for a
//! [`WalkConfig`](super::WalkConfig) variant at its defaults (REVIEW and BOX are both
//! [`WalkConfig::Review`](super::WalkConfig::Review); VSC, PB and CONV are
//! [`WalkConfig::Scene`](super::WalkConfig::Scene) traversals).

/// A walk mode, by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WalkMode {
    /// CSearch over disk cells with the index cache and prefetching (Shou 2002 §4.4).
    Review,
    /// Plain BOX queries over disk cells.
    Box,
    /// The current viewcell's PVS, neighbours prefetched (a database built with
    /// visibility).
    Pvs,
    /// The HDoV-tree searched from the current viewcell under η (a database built
    /// with visibility and the tree).
    Visual,
    /// The memory scene tree traversed by VSC under η (a database built with
    /// visibility).
    Vsc,
    /// The memory scene tree under a polygon budget (PB).
    Pb,
    /// The memory scene tree with view frustum culling only (CONV).
    Conv,
}

impl WalkMode {
    /// Every mode, in the order the CLI's help lists them.
    pub const ALL: [WalkMode; 7] = [
        WalkMode::Review,
        WalkMode::Box,
        WalkMode::Pvs,
        WalkMode::Visual,
        WalkMode::Vsc,
        WalkMode::Pb,
        WalkMode::Conv,
    ];

    /// The mode's name, as the CLI's `--mode` spells it and [`str::parse`] reads it.
    pub fn name(self) -> &'static str {
        match self {
            WalkMode::Review => "review",
            WalkMode::Box => "box",
            WalkMode::Pvs => "pvs",
            WalkMode::Visual => "visual",
            WalkMode::Vsc => "vsc",
            WalkMode::Pb => "pb",
            WalkMode::Conv => "conv",
        }
    }

    /// Whether the mode walks the memory scene tree (VSC, PB, CONV).
    pub fn over_scene_tree(self) -> bool {
        matches!(self, WalkMode::Vsc | WalkMode::Pb | WalkMode::Conv)
    }
}

impl std::fmt::Display for WalkMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for WalkMode {
    type Err = String;

    /// ```
    /// use flaneur::walk::WalkMode;
    /// assert_eq!("PVS".parse::<WalkMode>(), Ok(WalkMode::Pvs));
    /// assert!("walk".parse::<WalkMode>().unwrap_err().contains("review, box, pvs"));
    /// ```
    fn from_str(s: &str) -> std::result::Result<WalkMode, String> {
        let lower = s.to_ascii_lowercase();
        WalkMode::ALL
            .into_iter()
            .find(|m| m.name() == lower)
            .ok_or_else(|| {
                let names: Vec<_> = WalkMode::ALL.iter().map(|m| m.name()).collect();
                format!("unknown mode '{s}' ({})", names.join(", "))
            })
    }
}
