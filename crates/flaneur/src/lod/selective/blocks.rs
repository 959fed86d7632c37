//! El-Sana's view-dependence blocks (El-Sana's client-server paper, §4–6) over the
//! vertex hierarchy: the hierarchy cut into blocks of a few levels by parenthood and
//! siblings, each block the splits of a node and its descendants down to the next
//! block level, named by its top node. A client refines on its own from the blocks it
//! holds ([`SelectiveClient`]), and asks for blocks by name with switch-down messages:
//! the blocks its view wants a split from, and ahead of need the blocks below a split
//! that reached its block's last level (his "lower quarter"). The server sends each
//! block whole, with the blocks above it and those the partial order forces, so the
//! client never lacks a forced split; when idle it predicts which blocks the client's
//! next view will want and sends them unasked, and the client keeps or discards each by
//! its name.

use std::collections::{BTreeSet, HashMap, HashSet, VecDeque};

use super::{stream::view_test, VsplitPacket};
use super::{Front, NodeName, SelectiveBase, SelectiveClient, SelectiveSource, VertexHierarchy};
use crate::error::{Error, Result};
use crate::lod::refine::{Criteria, View};

/// One block: its top node's name and the packets of every split in it, top-down.
#[derive(Clone, Debug, PartialEq)]
pub struct Block {
    /// The block's name: its top node's.
    pub top: NodeName,
    /// The packets of its splits, parents before children.
    pub packets: Vec<VsplitPacket>,
}

impl VertexHierarchy {
    /// The top of the block of `levels` levels that holds `node`'s split: its ancestor
    /// (or itself) at the nearest block level above.
    pub fn block_top(&self, node: u32, levels: u32) -> u32 {
        let mut n = node;
        while !self.nodes[n as usize].depth.is_multiple_of(levels) {
            n = self.nodes[n as usize].parent.expect("a node below a root");
        }
        n
    }

    /// The nodes whose splits the block topped by `top` holds, top-down: those below
    /// it, itself included, above the next block level.
    pub fn block_nodes(&self, top: u32, levels: u32) -> Vec<u32> {
        let bottom = self.nodes[top as usize].depth + levels;
        let mut nodes = Vec::new();
        let mut queue = VecDeque::from([top]);
        while let Some(n) = queue.pop_front() {
            if let Some([l, r]) = self.children(n) {
                nodes.push(n);
                if self.nodes[n as usize].depth + 1 < bottom {
                    queue.extend([l, r]);
                }
            }
        }
        nodes
    }
}

/// The top of the block of `levels` levels that holds the split of the node `name`
/// names: a right shift to the block level.
pub fn block_of(name: &NodeName, levels: u32) -> NodeName {
    name.up(name.depth() % levels)
}

/// A server's session of blocks: the blocks it sent, and the front they make.
#[derive(Clone, Debug)]
pub struct BlockServer {
    sent: Front,
    /// The sent front's nodes: what a prediction's pass visits.
    live: BTreeSet<u32>,
    blocks: HashSet<u32>,
    /// Blocks the client released and was not sent again: above the sent front, so a
    /// prediction looks at them apart.
    released: BTreeSet<u32>,
    levels: u32,
    criteria: Criteria,
}

impl BlockServer {
    /// A session of blocks of `levels` levels (at least 1) that has sent the base mesh.
    pub fn new(source: &SelectiveSource, levels: u32) -> Result<BlockServer> {
        if levels == 0 {
            return Err(Error::Invalid("blocks of 0 levels: give at least 1".into()));
        }
        Ok(BlockServer {
            sent: source.hierarchy().roots(),
            live: (0..source.hierarchy().roots as u32).collect(),
            blocks: HashSet::new(),
            released: BTreeSet::new(),
            levels,
            criteria: Criteria::default(),
        })
    }

    /// The blocks sent so far.
    pub fn sent_blocks(&self) -> usize {
        self.blocks.len()
    }

    /// The session's own bytes: its front's tags and nodes, and the blocks' names
    /// (the source is shared).
    pub fn memory(&self) -> usize {
        self.sent.active.capacity()
            + 40 * (self.live.len() + self.released.len())
            + 16 * self.blocks.capacity()
    }

    /// The blocks `tops` name that were not sent (a switch-down), each after the
    /// blocks above it that were not, and with the blocks the partial order forces a
    /// split from, in the order a client installs them. An `Err` naming a top the
    /// hierarchy has not, or that is no block's top.
    pub fn send(&mut self, source: &SelectiveSource, tops: &[NodeName]) -> Result<Vec<Block>> {
        let h = source.hierarchy();
        let mut queue = VecDeque::new();
        for name in tops {
            let n = h
                .find(name)
                .ok_or_else(|| Error::Invalid(format!("no node {name:?} in the hierarchy")))?;
            if !h.nodes[n as usize].depth.is_multiple_of(self.levels) {
                return Err(Error::Invalid(format!(
                    "node {name:?} is no block's top: blocks are {} levels",
                    self.levels
                )));
            }
            queue.push_back(n);
        }
        let mut out = Vec::new();
        while let Some(top) = queue.pop_front() {
            self.send_one(h, source, top, &mut queue, &mut out)?;
        }
        Ok(out)
    }

    /// Sends block `top` if it was not, its parent block first; the blocks its splits
    /// force go on `queue`.
    fn send_one(
        &mut self,
        h: &VertexHierarchy,
        source: &SelectiveSource,
        top: u32,
        queue: &mut VecDeque<u32>,
        out: &mut Vec<Block>,
    ) -> Result<()> {
        if self.blocks.contains(&top) || h.children(top).is_none() {
            return Ok(());
        }
        if let Some(p) = h.parent(top) {
            self.send_one(h, source, h.block_top(p, self.levels), queue, out)?;
        }
        self.blocks.insert(top);
        self.released.remove(&top);
        let nodes = h.block_nodes(top, self.levels);
        for &n in &nodes {
            if !self.sent.is_active(n) {
                continue;
            }
            for d in self.sent.split(h, n)? {
                let [l, r] = h.children(d).expect("a split node");
                self.live.remove(&d);
                self.live.extend([l, r]);
                let b = h.block_top(d, self.levels);
                if !self.blocks.contains(&b) {
                    queue.push_back(b);
                }
            }
        }
        out.push(Block {
            top: h.name(top),
            packets: nodes.into_iter().map(|n| source.packet(n)).collect(),
        });
        Ok(())
    }

    /// Forgets that the blocks `tops` name were sent: the client dropped them from its
    /// cache (El-Sana §6.1), and will ask again for what it needs of them. An `Err`
    /// naming a block that was not sent, or one below which a block is still held.
    pub fn release(&mut self, source: &SelectiveSource, tops: &[NodeName]) -> Result<()> {
        let h = source.hierarchy();
        let mut released = HashSet::new();
        for name in tops {
            let top = h
                .find(name)
                .filter(|t| self.blocks.contains(t))
                .ok_or_else(|| Error::Invalid(format!("block {name:?} was not sent")))?;
            released.insert(top);
        }
        for &top in &released {
            for n in h.block_nodes(top, self.levels) {
                let below = h.children(n).expect("a block's node splits");
                if let Some(&b) = below
                    .iter()
                    .find(|&b| self.blocks.contains(b) && !released.contains(b))
                {
                    return Err(Error::Invalid(format!(
                        "block {:?} released while block {:?} below it is held",
                        h.name(top),
                        h.name(b)
                    )));
                }
            }
        }
        for b in &released {
            self.blocks.remove(b);
        }
        self.released.extend(released);
        Ok(())
    }

    /// Idle-time prediction: the blocks that `view` under `tau` will want a split from
    /// that were not sent, or were released since, at most `max` of them asked for
    /// (with what they bring).
    pub fn predict(
        &mut self,
        source: &SelectiveSource,
        view: &View,
        tau: f32,
        max: usize,
    ) -> Result<Vec<Block>> {
        let test = view_test(view, tau, self.criteria)?;
        let h = source.hierarchy();
        let mut wanted = Vec::new();
        for &n in &self.live {
            if wanted.len() >= max {
                break;
            }
            if source.qrefine(&test, n) {
                let b = h.block_top(n, self.levels);
                if !self.blocks.contains(&b) && !wanted.contains(&b) {
                    wanted.push(b);
                }
            }
        }
        // A released block's top is split on the sent front: the view may want it again.
        for &b in &self.released {
            if wanted.len() >= max {
                break;
            }
            if source.qrefine(&test, b) && !wanted.contains(&b) {
                wanted.push(b);
            }
        }
        let names: Vec<NodeName> = wanted.into_iter().map(|b| h.name(b)).collect();
        self.send(source, &names)
    }
}

/// What a client asks for after a view (El-Sana's switch-down): the blocks its view
/// wants a split from now, and those below a split that reached its block's last level.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SwitchDown {
    /// Blocks the view wants a split from that the client lacks.
    pub needed: Vec<NodeName>,
    /// Blocks below splits that reached their block's last level, asked ahead.
    pub ahead: Vec<NodeName>,
    /// Blocks the client dropped from its cache (a switch-up): the server forgets it
    /// sent them ([`BlockServer::release`]).
    pub released: Vec<NodeName>,
}

/// A block a client holds: the nodes whose splits it brought, top-down, and the last
/// view its mesh used it in.
#[derive(Clone, Debug)]
struct Held {
    nodes: Vec<NodeName>,
    used: u64,
}

/// A client of blocks: a [`SelectiveClient`] fed by whole blocks, and their names.
///
/// Its cache (El-Sana §6.1) keeps every block it is sent up to a capacity; past it, it
/// drops the blocks its mesh does not use, those furthest below the blocks in use
/// first (so the level just below them stays, and the levels above are in use), then
/// the least recently used (a block's use is counted at the views that find the cache
/// holding more than the capacity; below it there is nothing to drop, and no view pays
/// for a look at every block). A block is dropped only from the bottom of what it holds,
/// and never when a split run goes on into another block. The blocks dropped are named
/// to the server with the next switch message, and asked for again if a view wants
/// them.
#[derive(Clone, Debug)]
pub struct BlockClient {
    client: SelectiveClient,
    held: HashMap<NodeName, Held>,
    levels: u32,
    capacity: usize,
    views: u64,
    /// Blocks that came and were held already (a server's prediction, or twice).
    pub discarded: usize,
    /// Blocks dropped from the cache.
    pub dropped: usize,
}

impl BlockClient {
    /// A client of blocks of `levels` levels that has the base mesh, and keeps every
    /// block it is sent.
    pub fn new(base: SelectiveBase, levels: u32) -> BlockClient {
        BlockClient {
            client: SelectiveClient::new(base).dropping(),
            held: HashMap::new(),
            levels: levels.max(1),
            capacity: usize::MAX,
            views: 0,
            discarded: 0,
            dropped: 0,
        }
    }

    /// The client with a cache of at most `blocks` blocks beyond those its mesh uses.
    pub fn with_capacity(self, blocks: usize) -> BlockClient {
        BlockClient {
            capacity: blocks,
            ..self
        }
    }

    /// Takes `blocks`, keeping each it does not hold and discarding the rest by name.
    /// An `Err` for a block that holds a split outside it, or one its hierarchy does
    /// not take (as [`SelectiveClient::receive`]).
    pub fn receive(&mut self, blocks: &[Block]) -> Result<()> {
        for b in blocks {
            if self.held.contains_key(&b.top) {
                self.discarded += 1;
                continue;
            }
            if let Some(p) = b
                .packets
                .iter()
                .find(|p| block_of(&p.node, self.levels) != b.top)
            {
                return Err(Error::Invalid(format!(
                    "block {:?} holds the split of node {:?}, which is not in it",
                    b.top, p.node
                )));
            }
            self.client.receive(&b.packets)?;
            let nodes = b.packets.iter().map(|p| p.node.clone()).collect();
            self.held.insert(
                b.top.clone(),
                Held {
                    nodes,
                    used: self.views,
                },
            );
        }
        Ok(())
    }

    /// Brings the mesh to `view` under `tau` with the blocks held, and says which to
    /// ask for and which it dropped from its cache.
    pub fn select(&mut self, view: &View, tau: f32) -> Result<SwitchDown> {
        self.views += 1;
        let missing = self.client.select(view, tau)?;
        let mut down = SwitchDown::default();
        for n in &missing {
            let b = block_of(n, self.levels);
            if !down.needed.contains(&b) {
                down.needed.push(b);
            }
        }
        for (n, splits) in self.client.last_splits() {
            if (n.depth() + 1) % self.levels != 0 {
                continue;
            }
            for (right, more) in [(false, splits[0]), (true, splits[1])] {
                let child = NodeName {
                    tree: n.tree,
                    node: n.node.child(right),
                };
                if more && !self.client.holds_split(&child) && !down.ahead.contains(&child) {
                    down.ahead.push(child);
                }
            }
        }
        down.released = self.evict()?;
        Ok(down)
    }

    /// Drops blocks the mesh does not use while more than the capacity are held
    /// beyond those it does. The blocks dropped.
    fn evict(&mut self) -> Result<Vec<NodeName>> {
        if self.held.len() <= self.capacity {
            // Not full: nothing to drop, and recency is counted from when it is.
            return Ok(Vec::new());
        }
        let in_use: HashSet<NodeName> = self
            .held
            .keys()
            .filter(|top| self.client.is_split(top))
            .cloned()
            .collect();
        for top in &in_use {
            self.held.get_mut(top).expect("held").used = self.views;
        }
        let mut released = Vec::new();
        while self.held.len() - in_use.len() > self.capacity {
            let mut candidates = self.droppable_groups(&in_use);
            if candidates.is_empty() {
                break;
            }
            // Furthest below the blocks in use first, then least recently used.
            candidates.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
            for (_, _, group, nodes) in candidates {
                if self.held.len() - in_use.len() <= self.capacity {
                    break;
                }
                self.client.drop_splits(&nodes)?;
                for top in group {
                    self.held.remove(&top);
                    self.dropped += 1;
                    released.push(top);
                }
            }
        }
        Ok(released)
    }

    /// The groups of blocks not in use that may be dropped now, each with how far
    /// below the blocks in use it lies and when it was last used, its tops, and its
    /// nodes parents first. A group is the blocks that split runs tie together
    /// (a crease run may reach into other trees), dropped together or not at all.
    #[allow(clippy::type_complexity)]
    fn droppable_groups(
        &self,
        in_use: &HashSet<NodeName>,
    ) -> Vec<(u32, u64, Vec<NodeName>, Vec<NodeName>)> {
        let mut tops: Vec<&NodeName> = self.held.keys().filter(|t| !in_use.contains(*t)).collect();
        tops.sort();
        let mut seen = HashSet::new();
        let mut groups = Vec::new();
        for top in tops {
            if seen.contains(top) {
                continue;
            }
            let group = self.tied(top);
            seen.extend(group.iter().cloned());
            if group.iter().any(|t| in_use.contains(t)) {
                continue;
            }
            let mut nodes: Vec<NodeName> = group
                .iter()
                .flat_map(|t| self.held[t].nodes.iter().cloned())
                .collect();
            nodes.sort_by_key(|n| n.depth());
            if !self.client.can_drop(&nodes) {
                continue;
            }
            let below = group.iter().map(|t| self.below_use(t, in_use)).max();
            let used = group.iter().map(|t| self.held[t].used).max();
            groups.push((below.unwrap_or(0), used.unwrap_or(0), group, nodes));
        }
        groups
    }

    /// The held blocks that split runs tie to block `top`, itself first.
    fn tied(&self, top: &NodeName) -> Vec<NodeName> {
        let mut group = vec![top.clone()];
        let mut next = 0;
        while next < group.len() {
            let nodes = &self.held[&group[next]].nodes;
            next += 1;
            for n in nodes {
                for m in self.client.run_of(n) {
                    let b = block_of(&m, self.levels);
                    if self.held.contains_key(&b) && !group.contains(&b) {
                        group.push(b);
                    }
                }
            }
        }
        group
    }

    /// How many block levels `top` lies below the nearest block in use above it (the
    /// roots' level counting as in use).
    fn below_use(&self, top: &NodeName, in_use: &HashSet<NodeName>) -> u32 {
        let mut levels = 0;
        let mut at = top.clone();
        while at.depth() > 0 {
            at = block_of(&at.up(1), self.levels);
            levels += 1;
            if in_use.contains(&at) {
                break;
            }
        }
        levels
    }

    /// The selective client the blocks feed.
    pub fn client(&self) -> &SelectiveClient {
        &self.client
    }

    /// Blocks held.
    pub fn blocks(&self) -> usize {
        self.held.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::dag::{Dag, DagConstruction};
    use crate::lod::pm::ProgressiveMesh;
    use crate::lod::selective::testing::{canonical, random_view};
    use rand::{Rng, SeedableRng};

    /// Random views of `mesh`, each asked for block by block until the client lacks
    /// nothing: its mesh is a local refiner's after each, no forced split is ever
    /// missing, and the blocks a prediction sent are discarded when they come again.
    fn blocks_refine_as_a_local_refiner(
        mesh: &crate::scene::Mesh,
        seed: u64,
        capacity: Option<usize>,
    ) -> BlockClient {
        let pm = ProgressiveMesh::build(mesh).unwrap();
        let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
        let source = SelectiveSource::new(&pm, &dag).unwrap();
        let h = source.hierarchy();
        let mut server = BlockServer::new(&source, 4).unwrap();
        let mut client = BlockClient::new(source.base(), 4);
        if let Some(blocks) = capacity {
            client = client.with_capacity(blocks);
        }
        let mut local = h.roots();
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let (mut asked, mut ahead) = (0, 0);
        for step in 0..200 {
            let view = random_view(&mut rng, mesh);
            let tau = rng.gen_range(0.0005..0.01);
            if step % 10 == 5 {
                // Idle time: the server sends what it predicts this view wants.
                let predicted = server.predict(&source, &view, tau, 8).unwrap();
                client.receive(&predicted).unwrap();
            }
            source.select(&mut local, &view, tau).unwrap();
            loop {
                let down = client.select(&view, tau).unwrap();
                server.release(&source, &down.released).unwrap();
                ahead += down.ahead.len();
                if down.needed.is_empty() {
                    let blocks = server.send(&source, &down.ahead).unwrap();
                    client.receive(&blocks).unwrap();
                    break;
                }
                asked += 1;
                let mut tops = down.needed;
                tops.extend(down.ahead);
                let blocks = server.send(&source, &tops).unwrap();
                assert!(!blocks.is_empty(), "step {step}: nothing for {tops:?}");
                client.receive(&blocks).unwrap();
            }
            let theirs = local
                .triangles(h)
                .iter()
                .map(|t| t.map(|n| h.name(n)))
                .collect();
            assert_eq!(
                canonical(client.client().triangles()),
                canonical(theirs),
                "step {step}"
            );
        }
        // Most blocks come ahead of need.
        assert!(
            asked > 2 && ahead > 2 * asked,
            "asked {asked}, ahead {ahead}"
        );
        assert_eq!(client.blocks(), server.sent_blocks());
        client
    }

    #[test]
    fn a_client_of_blocks_refines_as_a_local_refiner() {
        let torus = blocks_refine_as_a_local_refiner(&crate::lod::bumpy_torus(1500), 3, None);
        let building = blocks_refine_as_a_local_refiner(&crate::lod::fixtures::building(), 4, None);
        assert_eq!(torus.dropped + building.dropped, 0);
        // Random views split and collapse.
        let (splits, collapses) = torus.client().operations();
        assert!(
            splits > 1000 && collapses > 1000,
            "{splits} splits, {collapses} collapses"
        );
    }

    #[test]
    fn a_client_whose_cache_drops_blocks_refines_as_a_local_refiner() {
        // Few blocks kept beyond those in use: most views drop some, and ask for some
        // of them again.
        for (mesh, seed) in [
            (crate::lod::bumpy_torus(1500), 5),
            (crate::lod::fixtures::building(), 6),
        ] {
            let client = blocks_refine_as_a_local_refiner(&mesh, seed, Some(4));
            assert!(client.dropped > 20, "dropped {}", client.dropped);
        }
    }

    #[test]
    fn a_released_block_is_sent_again_and_only_a_lowest_one_may_be_released() {
        let pm = ProgressiveMesh::build(&crate::lod::bumpy_torus(800)).unwrap();
        let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
        let source = SelectiveSource::new(&pm, &dag).unwrap();
        let h = source.hierarchy();
        let mut server = BlockServer::new(&source, 2).unwrap();
        // A block two levels down: its parent block comes first.
        let deep = (0..h.len() as u32)
            .find(|&n| h.nodes[n as usize].depth == 2 && h.children(n).is_some())
            .unwrap();
        let sent = server.send(&source, &[h.name(deep)]).unwrap();
        let tops: Vec<NodeName> = sent.iter().map(|b| b.top.clone()).collect();
        assert!(tops.contains(&h.name(deep)) && tops.len() >= 2, "{tops:?}");
        let parent = h.name(h.block_top(h.parent(deep).unwrap(), 2));
        let err = server.release(&source, &[parent]).unwrap_err().to_string();
        assert!(err.contains("below it is held"), "{err}");
        server.release(&source, &[h.name(deep)]).unwrap();
        let err = server
            .release(&source, &[h.name(deep)])
            .unwrap_err()
            .to_string();
        assert!(err.contains("was not sent"), "{err}");
        // A view that wants the released block's top split has it predicted again.
        let mut rng = rand::rngs::StdRng::seed_from_u64(9);
        let mesh = crate::lod::bumpy_torus(800);
        let view = (0..1000)
            .map(|_| random_view(&mut rng, &mesh))
            .find(|v| source.qrefine(&view_test(v, 1e-5, Criteria::default()).unwrap(), deep))
            .expect("a view that wants the node split");
        let predicted = server.predict(&source, &view, 1e-5, usize::MAX).unwrap();
        assert!(predicted.iter().any(|b| b.top == h.name(deep)));
        let again: Vec<NodeName> = predicted.iter().map(|b| b.top.clone()).collect();
        server.release(&source, &again).unwrap();
        let again = server.send(&source, &[h.name(deep)]).unwrap();
        assert_eq!(again.len(), 1);
        assert_eq!(
            again[0],
            sent[tops.iter().position(|t| *t == h.name(deep)).unwrap()]
        );
    }

    #[test]
    fn blocks_are_named_by_their_tops_and_hold_their_levels() {
        let pm = ProgressiveMesh::build(&crate::lod::bumpy_torus(800)).unwrap();
        let h = VertexHierarchy::new(&pm).unwrap();
        let levels = 3;
        let mut covered = 0;
        for top in (0..h.len() as u32).filter(|&n| h.block_top(n, levels) == n) {
            let nodes = h.block_nodes(top, levels);
            for &n in &nodes {
                assert_eq!(h.block_top(n, levels), top);
                assert_eq!(block_of(&h.name(n), levels), h.name(top));
            }
            covered += nodes.len();
        }
        // Every split is in exactly one block.
        assert_eq!(covered, pm.splits.len());
    }
}
