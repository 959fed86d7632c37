//! What the `pvs-prefetch` experiment writes: its CSVs, the summary beside Zheng's
//! Table 7.2 and Figs. 7.6–7.8, and the plots.

use super::*;

impl Report for PvsPrefetchReport {
    fn name(&self) -> &'static str {
        "pvs-prefetch"
    }

    /// Table 7.2's figures, one row per route and algorithm, the thesis's beside.
    fn to_csv(&self) -> String {
        let mut s = String::from(
            "route,algorithm,transactions,cache_swaps,objects_sent,objects_per_transaction,first_transaction_objects,objects_per_later_transaction,cells_requested,visual_misses,late_entries,cells_entered,peak_held_objects,thesis_transactions,thesis_cache_swaps,thesis_objects_per_transaction,thesis_first_transaction_objects\n",
        );
        for r in &self.routes {
            for rep in r.reports() {
                let t = &rep.totals;
                let th = thesis(r.route, rep.algorithm);
                s.push_str(&format!(
                    "{},{},{},{},{},{:.2},{},{:.2},{},{},{},{},{},{},{},{},{}\n",
                    r.route,
                    rep.algorithm,
                    t.transactions,
                    t.swaps,
                    t.objects_sent,
                    t.objects_per_transaction(),
                    t.first_transaction_objects,
                    t.objects_per_later_transaction(),
                    t.cells_requested,
                    t.visual_misses,
                    t.late_entries,
                    t.cells_entered,
                    t.peak_held_objects,
                    th.map_or(String::new(), |x| x.transactions.to_string()),
                    th.map_or(String::new(), |x| x.swaps.to_string()),
                    th.map_or(String::new(), |x| x.objects_per_transaction.to_string()),
                    th.map_or(String::new(), |x| x.first_transaction_objects.to_string()),
                ));
            }
        }
        s
    }

    /// The CSVs besides [`to_csv`](Self::to_csv)'s: (file name, text).
    fn extra_csvs(&self) -> Vec<(&'static str, String)> {
        vec![
            (STEPS_CSV, self.steps_csv()),
            (REGIONS_CSV, self.regions_csv()),
            (ROUTES_CSV, self.routes_csv()),
            (LATENCY_CSV, self.latency_csv()),
        ]
    }

    /// Table 7.2 beside the thesis's, the table's statistics, and the region sweep.
    fn markdown(&self) -> String {
        let c = &self.config;
        let st = &self.stats;
        let mut s = format!(
            "# pvs-prefetch — SNP against PBNP on {} (Zheng 2007 Table 7.2, Figs. 7.6–7.8)\n\n{}\n\n",
            self.place.name, self.place.description
        );
        s.push_str("The PVS table, measured, and as the thesis assumes it:\n\n| | ours | thesis |\n|---|---|---|\n");
        s.push_str(&format!(
            "| PVS, share of the {} objects | {:.2} % (mean {:.1} objects, {} to {}) | about 5 % |\n",
            st.scene_objects,
            100.0 * st.mean_share,
            st.mean_pvs,
            st.min_pvs,
            st.max_pvs
        ));
        s.push_str(&format!(
            "| share of a PVS that a side neighbour sees too | {:.1} % (over {} pairs) | about 60 % |\n",
            100.0 * st.side_overlap,
            st.side_pairs
        ));
        s.push_str(&format!(
            "| the same as intersection over union | {:.1} % | — |\n| diagonal neighbours; cells two apart | {:.1} %; {:.1} % | — |\n\n",
            100.0 * st.side_jaccard,
            100.0 * st.diagonal_overlap,
            100.0 * st.two_apart_overlap
        ));

        s.push_str("Table 7.2 and §7.5, ours (thesis's):\n\n|");
        for r in &self.routes {
            for rep in r.reports() {
                s.push_str(&format!(" | {} {}", r.name(), rep.algorithm));
            }
        }
        s.push_str(" |\n|---|---|---|---|---|\n");
        type Cell = fn(&SimTotals, Option<&ThesisColumn>) -> String;
        let rows: [(&str, Cell); 6] = [
            ("prefetch transactions", |t, th| {
                format!(
                    "{} ({})",
                    t.transactions,
                    th.map_or("—".into(), |x| x.transactions.to_string())
                )
            }),
            ("cache swaps", |t, th| {
                format!(
                    "{} ({})",
                    t.swaps,
                    th.map_or("—".into(), |x| x.swaps.to_string())
                )
            }),
            ("objects per transaction", |t, th| {
                format!(
                    "{:.1} ({})",
                    t.objects_per_transaction(),
                    th.map_or("—".into(), |x| x.objects_per_transaction.to_string())
                )
            }),
            ("objects in the first transaction", |t, th| {
                format!(
                    "{} ({})",
                    t.first_transaction_objects,
                    th.map_or("—".into(), |x| x.first_transaction_objects.to_string())
                )
            }),
            ("visual misses (objects; cells entered late)", |t, _| {
                format!("{}; {} (—)", t.visual_misses, t.late_entries)
            }),
            ("PVS rows requested", |t, _| {
                format!("{} (—)", t.cells_requested)
            }),
        ];
        for (name, cell) in rows {
            s.push_str(&format!("| {name}"));
            for r in &self.routes {
                for rep in r.reports() {
                    s.push_str(&format!(
                        " | {}",
                        cell(&rep.totals, thesis(r.route, rep.algorithm))
                    ));
                }
            }
            s.push_str(" |\n");
        }
        if self.routes.iter().all(|r| r.pages.is_some()) {
            s.push_str("| pages read (PVS records)");
            for r in &self.routes {
                for pages in r.pages.into_iter().flatten() {
                    s.push_str(&format!(" | {pages} (—)"));
                }
            }
            s.push_str(" |\n");
        }
        s.push_str("\nSNP → PBNP, ours (thesis's):\n\n| | transactions | cache swaps | objects per transaction |\n|---|---|---|---|\n");
        for r in &self.routes {
            let (a, b) = (&r.snp.totals, &r.pbnp.totals);
            let (ta, tb) = (thesis(r.route, "SNP"), thesis(r.route, "PBNP"));
            let th = |f: fn(&ThesisColumn) -> f64| match (ta, tb) {
                (Some(x), Some(y)) => change(f(x), f(y)),
                _ => "—".into(),
            };
            s.push_str(&format!(
                "| {} | {} ({}) | {} ({}) | {} ({}) |\n",
                r.name(),
                change(a.transactions as f64, b.transactions as f64),
                th(|x| x.transactions as f64),
                change(a.swaps as f64, b.swaps as f64),
                th(|x| x.swaps as f64),
                change(a.objects_per_transaction(), b.objects_per_transaction()),
                th(|x| x.objects_per_transaction),
            ));
        }
        if !self.sweep.is_empty() {
            s.push_str(&format!(
                "\nPBNP against its region size (the thesis gives none; a band at least one {} m step wide leaves no visual misses):\n\n\
                 | border (of the side) | band (m) | route | transactions | cache swaps | objects per transaction | visual misses |\n|---|---|---|---|---|---|---|\n",
                c.route.step
            ));
            for w in &self.sweep {
                let t = &w.totals;
                s.push_str(&format!(
                    "| {} | {} | {} | {} | {} | {:.1} | {} |\n",
                    w.border,
                    w.border * self.place.cell,
                    w.route,
                    t.transactions,
                    t.swaps,
                    t.objects_per_transaction(),
                    t.visual_misses
                ));
            }
        }
        if !self.latency.is_empty() {
            s.push_str(&format!(
                "\nUnder latency (ours; the thesis does not time transactions): a transaction asked at step t is \
                 answered at step t + L, so the frames of the next L steps draw without it; the viewer waits L \
                 steps at the start for the start-up transaction. A visual miss is an object of the current \
                 cell's PVS not on hand in a frame: objects summed over the route, and steps with any. LANP \
                 (ours) asks for PBNP's area and every walkable cell within the viewer's reach, as far as it goes \
                 in the round trip it has measured at the speed it has measured ({} m a step before it has \
                 moved), and its cache grows to hold them. With no round trip it is PBNP. SNP's and PBNP's \
                 transactions, swaps and objects do not depend on L: at every L they are Table 7.2's above.\n\n\
                 | route | L (steps) | SNP misses (steps) | PBNP misses (steps) | LANP misses (steps) | LANP cache swaps (SNP's) | LANP objects sent (SNP's) | LANP transactions (SNP's) | LANP peak cells, objects held (SNP's) |\n\
                 |---|---|---|---|---|---|---|---|---|\n",
                c.route.step
            ));
            for r in &self.routes {
                for &l in &c.latencies {
                    let get = |a: &str| self.at_latency(r.route, l, a);
                    let (Some(snp), Some(pbnp), Some(lanp)) =
                        (get("SNP"), get("PBNP"), get("LANP"))
                    else {
                        continue;
                    };
                    let m = |t: &SimTotals| format!("{} ({})", t.visual_misses, t.miss_steps);
                    s.push_str(&format!(
                        "| {} | {l} | {} | {} | {} | {} ({}) | {} ({}) | {} ({}) | {}, {} ({}, {}) |\n",
                        r.route,
                        m(snp),
                        m(pbnp),
                        m(lanp),
                        lanp.swaps,
                        snp.swaps,
                        lanp.objects_sent,
                        snp.objects_sent,
                        lanp.transactions,
                        snp.transactions,
                        lanp.peak_cached_cells,
                        lanp.peak_held_objects,
                        snp.peak_cached_cells,
                        snp.peak_held_objects
                    ));
                }
            }
        }
        s
    }

    /// Objects sent at each step per route and algorithm (Figs. 7.7, 7.8), the objects
    /// sent so far, the routes seen from above (Fig. 7.6), and the region sweep.
    fn plot(&self, dir: &Path) -> Result<()> {
        use crate::plot::{line_plot, LinePlot, Series};
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        for r in &self.routes {
            for rep in r.reports() {
                let fig = if r.route == 1 { "7.7" } else { "7.8" };
                line_plot(
                    &dir.join(steps_plot(r.route, rep.algorithm)),
                    &LinePlot {
                        title: format!(
                            "Objects sent at each step, {} {} (cf. Fig. {fig})",
                            r.name(),
                            rep.algorithm
                        ),
                        x_label: "step".into(),
                        y_label: "objects transmitted".into(),
                        series: vec![Series {
                            name: rep.algorithm.into(),
                            points: rep
                                .steps
                                .iter()
                                .map(|s| (s.step as f64, s.objects_sent as f64))
                                .collect(),
                        }],
                    },
                )?;
            }
            line_plot(
                &dir.join(cumulative_plot(r.route)),
                &LinePlot {
                    title: format!("Objects sent so far, {}", r.name()),
                    x_label: "step".into(),
                    y_label: "objects transmitted".into(),
                    series: r
                        .reports()
                        .iter()
                        .map(|rep| Series {
                            name: rep.algorithm.into(),
                            points: rep
                                .steps
                                .iter()
                                .scan(0usize, |sum, s| {
                                    *sum += s.objects_sent;
                                    Some((s.step as f64, *sum as f64))
                                })
                                .collect(),
                        })
                        .collect(),
                },
            )?;
        }
        line_plot(
            &dir.join(ROUTES_PLOT),
            &LinePlot {
                title: "The two routes seen from above (cf. Fig. 7.6)".into(),
                x_label: "x (m, east)".into(),
                y_label: "z (m, south)".into(),
                series: self
                    .routes
                    .iter()
                    .map(|r| Series {
                        name: r.name(),
                        points: r.positions.iter().map(|p| (p.x, p.z)).collect(),
                    })
                    .collect(),
            },
        )?;
        if !self.latency.is_empty() {
            let series = |f: fn(&SimTotals) -> f64| -> Vec<Series> {
                let mut out = Vec::new();
                for r in &self.routes {
                    for alg in LATENCY_ALGORITHMS {
                        out.push(Series {
                            name: format!("{} {alg}", r.name()),
                            points: self
                                .latency
                                .iter()
                                .filter(|w| w.route == r.route && w.algorithm == alg)
                                .map(|w| (w.latency as f64, f(&w.totals)))
                                .collect(),
                        });
                    }
                }
                out
            };
            line_plot(
                &dir.join(LATENCY_MISSES_PLOT),
                &LinePlot {
                    title: "Visual misses against latency".into(),
                    x_label: "latency (steps from asking to the answer)".into(),
                    y_label: "objects missing from frames, summed".into(),
                    series: series(|t| t.visual_misses as f64),
                },
            )?;
            line_plot(
                &dir.join(LATENCY_SWAPS_PLOT),
                &LinePlot {
                    title: "Cache swaps against latency".into(),
                    x_label: "latency (steps from asking to the answer)".into(),
                    y_label: "cache swaps along the route".into(),
                    series: series(|t| t.swaps as f64),
                },
            )?;
        }
        if self.sweep.is_empty() {
            return Ok(());
        }
        let sweep = |route: u8, f: fn(&SimTotals) -> f64| -> Vec<(f64, f64)> {
            self.sweep
                .iter()
                .filter(|w| w.route == route)
                .map(|w| (w.border, f(&w.totals)))
                .collect()
        };
        let mut counts = Vec::new();
        let mut misses = Vec::new();
        for r in &self.routes {
            counts.push(Series {
                name: format!("{}: transactions", r.name()),
                points: sweep(r.route, |t| t.transactions as f64),
            });
            counts.push(Series {
                name: format!("{}: cache swaps", r.name()),
                points: sweep(r.route, |t| t.swaps as f64),
            });
            misses.push(Series {
                name: r.name(),
                points: sweep(r.route, |t| t.visual_misses as f64),
            });
        }
        line_plot(
            &dir.join(REGIONS_PLOT),
            &LinePlot {
                title: "PBNP: transactions and cache swaps against region size".into(),
                x_label: "region border (fraction of the cell side)".into(),
                y_label: "count along the route".into(),
                series: counts,
            },
        )?;
        line_plot(
            &dir.join(MISSES_PLOT),
            &LinePlot {
                title: "PBNP: visual misses against region size".into(),
                x_label: "region border (fraction of the cell side)".into(),
                y_label: "objects missing on entering a cell".into(),
                series: misses,
            },
        )
    }
}
