"""Dynamics on a rig (Follow Rig): what playback reads of the Armature modifier that skins a mesh.

The simulation (core Simulation with ``rig=W``) runs in the mesh's rest space and playback shows
its displacement as an offset before the Armature modifier (frame_display.offset_mesh), so the
skinning carries it and the mesh as shape keys leave it (correctives included) stays the artist's.

- Weights W, read once per Player (Blender has no bulk access to vertex groups): for each vertex,
  its weights in the groups named like the armature's deforming bones, each row divided by its sum
  as the Armature modifier divides it. Bones no vertex is weighted to are left out (they move
  nothing); vertices weighted to no bone get a column of their own whose matrix is the mesh
  object's world matrix: the Armature modifier leaves them where they are (a warning says so).
- A frame of the rig, (bones + 1, 4, 4): each used bone's world skinning matrix, B = armature world
  x pose x rest⁻¹ x armature world⁻¹ x mesh world (the Armature modifier's object-space matrix,
  premultiplied by the mesh object's world matrix: a jump keyed on the armature object, the mesh
  object or a parent moves it), then the mesh object's world matrix itself. Read with foreach_get
  and NumPy, no loop over bones or vertices.
- The Attach group: the vertices of weight above ATTACH_WEIGHT, a handle held at the identity
  (zero displacement: where the rig puts them). Fill Attach from Armature (fill_attach) puts in it
  the vertices within a fraction of each deforming bone's length of the bone's segment.
- The artist's handles map into rest space: a handle with a controller by the inverse of the
  skinning at its vertices (their mean weights) A, A⁻¹ x mesh world x T x S (T its object-space
  transform, handles.transforms; S the skinning in object space when it was bound,
  bind_skinning); a handle without one is held where the rig puts its vertices (as Attach). So a
  controller counts its motion from where it was bound, and the vertices from where the rig put
  them then: bound in any pose of the rig, a handle holds its vertices where the rig puts them
  until its controller moves (an Empty that stays put then holds them where they were in the
  world; a bone of the rig that the vertices are weighted to holds them where that bone puts
  them, whatever the pose); moving the controller moves them from there, as it moves them off
  the rig.

Refused with a message (RigError): no Armature modifier, two of them, one without an armature, one
disabled in the viewport, with Preserve Volume (dual quaternions, not linear blend skinning), with
Bone Envelopes, a mask vertex group or Multi Modifier, one placed before the display, an armature
without deforming bones, no or an empty Attach group. Bones with scale or shear are skinned as the
Armature modifier skins them (the core takes affine bones; a singular one is refused by it).
"""

import hashlib

import bpy
import numpy as np

from .. import core as mdc
from .. import mesh_io

#: Attach group membership: the vertices whose weight is above this (a painted falloff of small
#: weights does not hold them).
ATTACH_WEIGHT = 0.5
#: The Armature modifier leaves a vertex whose weights sum to no more than this where it is
#: (armature_deform.cc's threshold).
MIN_WEIGHT = 1e-4
#: Fill Attach from Armature's default reach: a fraction of each bone's length around its segment.
ATTACH_REACH = 0.25


#: The cache's field holding the digest of the weights and Attach group its frames were made with.
WEIGHTS = "rig_weights"


class RigError(ValueError):
    """Follow Rig cannot run, with what is wrong and what to do."""


def follows(obj):
    """Whether obj's dynamics follow its rig."""
    dynamics = obj.modal_deform.dynamics
    return dynamics.enabled and dynamics.follow_rig


def armature_modifiers(obj):
    return [m for m in obj.modifiers if m.type == "ARMATURE"]


def armature_modifier(obj):
    """The one Armature modifier of obj, checked (RigError naming what is wrong)."""
    found = armature_modifiers(obj)
    what = f"Follow Rig on '{obj.name}'"
    if not found:
        raise RigError(f"{what}: no Armature modifier skins it: add one, or turn Follow Rig off")
    if len(found) > 1:
        names = ", ".join(f"'{m.name}'" for m in found)
        raise RigError(f"{what}: {len(found)} Armature modifiers ({names}): keep one")
    modifier = found[0]
    label = f"{what}: Armature modifier '{modifier.name}'"
    armature = modifier.object
    if armature is None or armature.type != "ARMATURE":
        raise RigError(f"{label} has no armature (deleted?): choose one")
    if bpy.context.scene.objects.get(armature.name) != armature:
        raise RigError(f"{label}: armature '{armature.name}' is not in the scene")
    if not modifier.show_viewport:
        raise RigError(f"{label} is disabled in the viewport: enable it")
    if modifier.use_deform_preserve_volume:
        raise RigError(
            f"{label} uses Preserve Volume (dual quaternions), which the simulation does not "
            f"reproduce: turn Preserve Volume off"
        )
    if not modifier.use_vertex_groups or modifier.use_bone_envelopes:
        raise RigError(
            f"{label}: Follow Rig reads the bones' vertex groups only: bind to Vertex Groups, "
            f"Bone Envelopes off"
        )
    if modifier.vertex_group or modifier.use_multi_modifier:
        raise RigError(f"{label} is masked (a vertex group or Multi Modifier): clear the mask")
    return modifier


def check_order(obj, display):
    """RigError when the display modifier `display` (None: not made yet) comes after obj's Armature
    modifier: its offset would be added to the skinned mesh instead of carried by the skinning."""
    modifier = armature_modifier(obj)
    if display is not None and list(obj.modifiers).index(display) > list(obj.modifiers).index(
        modifier
    ):
        raise RigError(
            f"Follow Rig on '{obj.name}': Armature modifier '{modifier.name}' comes before "
            f"'{display.name}', which must come first: the display is put back first"
        )


def deform_bones(armature):
    """The names of the armature's deforming bones, in its order, read in two calls (their names,
    then use_deform in bulk) rather than two per bone: every frame shown reads them (signature())."""
    bones = armature.data.bones
    deform = np.empty(len(bones), bool)
    bones.foreach_get("use_deform", deform)
    return [name for name, used in zip(bones.keys(), deform) if used]


def signature(obj):
    """What the cached frames on a rig depend on besides its motion: the armature, its deforming
    bones (a bone renamed or deleted) and the Attach group (weights are read with the Player)."""
    modifier = next(iter(armature_modifiers(obj)), None)
    armature = modifier.object if modifier is not None else None
    bones = tuple(deform_bones(armature)) if armature is not None and armature.data else ()
    return (
        modifier.name if modifier else "",
        armature.name if armature else "",
        bones,
        obj.modal_deform.dynamics.attach_group,
    )


def action_curves(obj):
    """The animation curves that move obj's rig, as (path, F-curve): the armature object's (its
    bones' too) and the mesh object's own; paths "rig:object:data_path[index]"."""
    from .frame_keys import action_fcurves

    modifier = next(iter(armature_modifiers(obj)), None)
    found = []
    for owner in (modifier.object if modifier else None, obj):
        if owner is None:
            continue
        for curve in action_fcurves(owner.animation_data) or ():
            found.append((f"rig:{owner.name}:{curve.data_path}[{curve.array_index}]", curve))
    return sorted(found, key=lambda item: item[0])


def world_skinning(armature, pose, rest_inverse, mesh_world):
    """Bones' world skinning matrices (b, 4, 4): armature world x pose x rest⁻¹ x armature world⁻¹
    x mesh world, from their pose matrices `pose` and inverse rest matrices (armature space)."""
    armature_world = np.array(armature.matrix_world)
    inverse = affine_inverse(
        armature_world,
        f"Follow Rig: armature '{armature.name}' is scaled to nothing (its matrix is singular)",
    )
    return armature_world @ (pose @ rest_inverse) @ (inverse @ mesh_world)


def affine_inverse(M, refusal):
    """The inverse of an affine 4x4 matrix M (last row 0, 0, 0, 1, as an object's matrix); RigError
    `refusal` when it is singular. The 3x3 part's adjugate over its determinant (its rows' cross
    products), with no LAPACK call, which waits milliseconds for OpenBLAS's threads on a busy
    machine where the frame's own work of this is microseconds."""
    R, t = M[:3, :3], M[:3, 3]
    cofactors = np.cross(R[[1, 2, 0]], R[[2, 0, 1]])  # rows r1 x r2, r2 x r0, r0 x r1
    determinant = float((R[0] * cofactors[0]).sum())
    if determinant == 0.0 or not np.isfinite(determinant):
        raise RigError(refusal)
    inverse = np.eye(4)
    inverse[:3, :3] = cofactors.T / determinant
    inverse[:3, 3] = -(inverse[:3, :3] * t).sum(axis=1)
    return inverse


class CompressedRows:
    """Skinning weights as compressed rows, read by the core as a sparse matrix's (tocsr())."""

    def __init__(self, shape, indptr, indices, data):
        self.shape, self.indptr, self.indices, self.data = shape, indptr, indices, data

    def tocsr(self):
        return self


def _read_groups(obj, columns_of_groups, attach_index):
    """One walk over the vertices: (rows (nonzero,), group indices, weights) of the groups in
    `columns_of_groups` (a group index -> column, -1 for others), and the Attach weights (n,)."""
    rows, groups, values = [], [], []
    attach = np.zeros(len(obj.data.vertices))
    for v in obj.data.vertices:
        for g in v.groups:
            if g.group == attach_index:
                attach[v.index] = g.weight
            if columns_of_groups.get(g.group, -1) >= 0 and g.weight > 0.0:
                rows.append(v.index)
                groups.append(g.group)
                values.append(g.weight)
    columns = np.array([columns_of_groups[g] for g in groups], np.int64)
    return np.array(rows, np.int64), columns, np.array(values, np.float64), attach


class Rig:
    """obj's rig as the simulation takes it, read once: the weights (``weights``, CompressedRows
    (n, columns)), the bones they name (``bones``), the Attach vertices (``attach``) and
    ``warnings``. ``frame(obj)`` reads a frame of the rig, ``bones_of(frame)`` the simulation's
    matrices of it. Raises RigError."""

    def __init__(self, obj, num_vertices):
        modifier = armature_modifier(obj)
        self.armature = armature = modifier.object
        self.warnings = []
        names = deform_bones(armature)
        if not names:
            raise RigError(f"Follow Rig: armature '{armature.name}' has no deforming bones")
        group_name = obj.modal_deform.dynamics.attach_group
        if not group_name:
            raise RigError(
                f"Follow Rig on '{obj.name}': no Attach group: Fill Attach from Armature, or choose "
                f"the vertex group the rig holds"
            )
        attach_group = obj.vertex_groups.get(group_name)
        if attach_group is None:
            raise RigError(f"Follow Rig: the Attach group '{group_name}' does not exist")
        columns = {}
        for column, name in enumerate(names):
            group = obj.vertex_groups.get(name)
            if group is not None:
                columns[group.index] = column
        rows, cols, values, attach = _read_groups(obj, columns, attach_group.index)
        self.attach = np.flatnonzero(attach > ATTACH_WEIGHT).astype(np.int32)
        if not self.attach.size:
            raise RigError(
                f"Follow Rig: the Attach group '{group_name}' holds no vertex (none of weight above "
                f"{ATTACH_WEIGHT:g}): Fill Attach from Armature, or paint it"
            )
        # As the Armature modifier, a vertex whose weights sum to at most MIN_WEIGHT is not skinned.
        kept = (np.bincount(rows, values, minlength=num_vertices) > MIN_WEIGHT)[rows]
        rows, cols, values = rows[kept], cols[kept], values[kept]
        # Bones no vertex is weighted to are left out; the used ones keep the armature's order.
        used = np.unique(cols)
        if not used.size:
            raise RigError(
                f"Follow Rig: no vertex of '{obj.name}' is in a vertex group named like a deforming "
                f"bone of '{armature.name}': weight the mesh to the armature"
            )
        cols = np.searchsorted(used, cols)
        self.bones = [names[i] for i in used]
        order = np.lexsort((cols, rows))
        rows, cols, values = rows[order], cols[order], values[order]
        counts = np.bincount(rows, minlength=num_vertices)
        unweighted = np.flatnonzero(counts == 0)
        if unweighted.size:
            self.warnings.append(
                f"{unweighted.size} vertices are weighted to no bone (vertex {unweighted[0]} "
                f"first): they stay where the Armature modifier leaves them, unskinned"
            )
            # Their column, the last: the mesh object's world matrix.
            rows = np.concatenate((rows, unweighted))
            cols = np.concatenate((cols, np.full(unweighted.size, len(self.bones))))
            values = np.concatenate((values, np.ones(unweighted.size)))
            order = np.argsort(rows, kind="stable")
            rows, cols, values = rows[order], cols[order], values[order]
            counts = np.bincount(rows, minlength=num_vertices)
        self.unskinned = bool(unweighted.size)
        pointers = np.concatenate(([0], np.cumsum(counts)))
        sums = np.add.reduceat(values, pointers[:-1])
        values = values / np.repeat(sums, counts)
        self.weights = CompressedRows(
            (num_vertices, len(self.bones) + self.unskinned), pointers, cols, values
        )
        rest = np.array([np.array(armature.data.bones[name].matrix_local) for name in self.bones])
        self._rest_inverse = np.linalg.inv(rest)
        self._index_pose(armature.pose.bones)
        self._counts, self._pointers, self._columns = counts, pointers, cols
        digest = hashlib.blake2b(repr(self.bones).encode(), digest_size=16)
        for array in (pointers, cols, values, self.attach):
            digest.update(np.ascontiguousarray(array).tobytes())
        self.digest = digest.hexdigest()  #: of the weights as read, for the cache (WEIGHTS)

    def _index_pose(self, pose_bones):
        """Where the used bones are among the pose's (pose_bones.keys(): their names in order)."""
        self._pose_names = pose_bones.keys()
        self._pose_index = np.array([self._pose_names.index(name) for name in self.bones])
        self._matrices = np.empty(16 * len(self._pose_names), np.float32)

    def frame(self, obj):
        """The rig now, (bones + 1, 4, 4) float64: each used bone's world skinning matrix, then the
        mesh object's world matrix. A deforming bone renamed or deleted changes signature(): the
        Player reads a new Rig; other bones added, deleted or renamed are indexed again here."""
        armature = self.armature
        pose_bones = armature.pose.bones
        if pose_bones.keys() != self._pose_names:
            self._index_pose(pose_bones)
        pose_bones.foreach_get("matrix", self._matrices)
        pose = self._matrices.reshape(-1, 4, 4).transpose(0, 2, 1)[self._pose_index]
        mesh_world = np.array(obj.matrix_world)
        bones = world_skinning(armature, pose, self._rest_inverse, mesh_world)
        return np.concatenate((bones, mesh_world[None]))

    def bones_of(self, frame):
        """The simulation's bones of a frame (Rig.frame): the used bones, and the mesh object's
        world matrix for the unskinned vertices' column when there are any."""
        return frame if self.unskinned else frame[:-1]

    def handle_weights(self, indices):
        """The mean weight row (columns,) of the vertices `indices`."""
        rows = np.repeat(np.arange(len(self._counts)), self._counts)
        inside = np.isin(rows, indices)
        total = np.bincount(
            self._columns[inside], self.weights.data[inside], minlength=self.weights.shape[1]
        )
        return total / len(indices)

    def to_rest(self, transforms, frame, handle_weights, handles):
        """The handles' object-space transforms T (handles.transforms) in rest space on the rig at
        `frame`: A⁻¹ x mesh world x T x S, A the skinning blended by the handle's mean weights, S
        the skinning it was bound in (Handle.bind_skinning), made rigid about its centre; the
        identity for a handle without a controller (None in `handle_weights`)."""
        bones, mesh_world = self.bones_of(frame), frame[-1]
        result = []
        for T, weights, handle in zip(transforms, handle_weights, handles):
            if weights is None:
                result.append(np.eye(4))
                continue
            inverse = affine_inverse(
                np.einsum("b,bij->ij", weights, bones),
                f"Follow Rig: the bones under handle '{handle.name}' blend to a singular matrix "
                f"this frame: a bone is scaled to nothing",
            )
            target = mesh_world @ T @ handle.bind_skinning
            result.append(mdc.nearest_rigid(inverse @ target, handle.centre))
        return result

    def skinned(self, X, frame):
        """X (n, 3) rest-space positions skinned at a frame of the rig, in the mesh object's space
        (what the Armature modifier shows)."""
        inverse = affine_inverse(
            frame[-1], "Follow Rig: the mesh object is scaled to nothing (its matrix is singular)"
        )
        return mdc.skin(X, self.weights, inverse @ self.bones_of(frame))


def bind_skinning(obj, indices):
    """The skinning a handle bound now records (handles.bind): obj's Armature modifier's in obj's
    space, the bones' matrices blended by the mean weights of the handle's vertices `indices` as
    Rig.handle_weights blends them (4x4 float64). The identity when no usable Armature modifier
    skins obj, and when it moves no vertex of the handle by more than float32 rounding (the rig's
    rest pose read back through Blender's float matrices)."""
    try:
        armature = armature_modifier(obj).object
        names = deform_bones(armature)
        mesh_world = np.array(obj.matrix_world)
        columns = {}
        for column, name in enumerate(names):
            group = obj.vertex_groups.get(name)
            if group is not None:
                columns[group.index] = column
        mean = np.zeros(len(names) + 1)  # the last: unskinned vertices, left where they are
        for i in indices:
            row = np.zeros(len(names) + 1)
            for g in obj.data.vertices[int(i)].groups:
                if columns.get(g.group, -1) >= 0 and g.weight > 0.0:
                    row[columns[g.group]] += g.weight
            total = row.sum()
            if total > MIN_WEIGHT:
                mean += row / total
            else:
                mean[-1] += 1.0
        mean /= len(indices)
        used = np.flatnonzero(mean[:-1])
        if not used.size:  # every vertex unskinned
            return np.eye(4)
        pose = np.array([np.array(armature.pose.bones[names[b]].matrix) for b in used])
        rest = np.array([np.array(armature.data.bones[names[b]].matrix_local) for b in used])
        bones = world_skinning(armature, pose, np.linalg.inv(rest), mesh_world)
        skinning = mean[-1] * np.eye(4) + np.linalg.solve(
            mesh_world, np.einsum("b,bij->ij", mean[used], bones)
        )
    except (RigError, np.linalg.LinAlgError):
        return np.eye(4)
    rest_positions = mesh_io.positions(obj.data)[indices]
    moved = rest_positions @ (skinning[:3, :3] - np.eye(3)).T + skinning[:3, 3]
    if np.abs(moved).max() <= 1e-6 * (1.0 + np.abs(rest_positions).max()):
        return np.eye(4)
    return skinning


def fill_attach(obj, reach=ATTACH_REACH):
    """Put into obj's Attach group (made, named "Attach", when it has none) every vertex within
    `reach` times a deforming bone's length of the bone's segment at rest, weight 1, the others
    out of it. Returns the number of vertices attached. RigError without an armature."""
    armature = armature_modifier(obj).object
    names = deform_bones(armature)
    if not names:
        raise RigError(f"armature '{armature.name}' has no deforming bones")
    # The bones at rest in the mesh object's space (the mesh bound to the rig's rest pose).
    to_mesh = np.linalg.solve(np.array(obj.matrix_world), np.array(armature.matrix_world))
    heads = np.array([tuple(armature.data.bones[n].head_local) + (1.0,) for n in names])
    tails = np.array([tuple(armature.data.bones[n].tail_local) + (1.0,) for n in names])
    heads, tails = (heads @ to_mesh.T)[:, :3], (tails @ to_mesh.T)[:, :3]
    V = mesh_io.positions(obj.data)
    near = np.zeros(len(V), bool)
    for head, tail in zip(heads, tails):
        axis = tail - head
        length = np.linalg.norm(axis)
        t = np.clip((V - head) @ axis / max(length * length, 1e-30), 0.0, 1.0)
        near |= np.linalg.norm(V - (head + t[:, None] * axis), axis=1) <= reach * length
    dynamics = obj.modal_deform.dynamics
    group = obj.vertex_groups.get(dynamics.attach_group) if dynamics.attach_group else None
    if group is None:
        group = obj.vertex_groups.new(name="Attach")
        dynamics.attach_group = group.name
    group.remove(list(range(len(V))))
    attached = np.flatnonzero(near).tolist()
    if attached:
        group.add(attached, 1.0, "REPLACE")
    return len(attached)
