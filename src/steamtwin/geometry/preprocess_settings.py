"""Settings and report of the point-cloud preprocessing chain (:mod:`.preprocess`).

Apart from the orchestration so that the filters, the registration (:mod:`.registration`) and
:func:`~steamtwin.geometry.preprocess.preprocess_views` all read them without an import cycle.
"""

from __future__ import annotations

from dataclasses import dataclass, field

#: Share of the scanned blade points that the fused, downsampled cloud keeps by default: the
#: method's ~150k scanned points per blade → ~80k after feature-preserving downsampling.
KEPT_SHARE = 80_000 / 150_000


@dataclass(frozen=True)
class PreprocessSettings:
    """Hyper-parameters of :func:`preprocess_views` (lengths in m).

    ``voxel`` is the feature scale for FPFH/RANSAC; ``icp_distance`` the ICP correspondence
    cut-off; ``target_points`` the size of the fused, downsampled cloud (None:
    :data:`KEPT_SHARE` of the scanned blade points, i.e. of the input less the reference
    spheres' points — the method's ~150k → ~80k at any scan density). ``sphere_radius`` is
    the nominal radius of the reference spheres on the fixture (default 5 mm, the virtual
    scanner's spheres on hp1; a scan folder's ``scan.json`` records its own; None: no sphere
    detection), ``sphere_tolerance`` the shell half-width of a sphere's points
    (twice the scanner's ±0.05 mm bound), ``sphere_min_points`` the fewest points a sphere is
    accepted with and ``sphere_match_distance`` how close (in the frame of the starting poses)
    two views' centres of one sphere must land (see :mod:`steamtwin.geometry.targets`).
    """

    outlier_neighbours: int = 50
    outlier_std_ratio: float = 2.0
    mls_neighbours: int = 30
    mls_max_shift: float = 0.05e-3  # the scanner's error bound
    voxel: float = 1.0e-3
    icp_distance: float = 0.4e-3
    ransac_iterations: int = 200_000
    min_overlap: float = 0.3  # overlap share below which a pair of views is not linked
    hypotheses: int = 4  # RANSAC runs (seeds) per view
    stability: float = 0.1  # ICP moves only along directions this well constrained (share)
    max_violation: float = 0.10  # free-space violation share above which a pose is rejected
    target_points: int | None = None
    feature_share: float = 0.25  # share of the kept points reserved for high-curvature regions
    joint_iterations: int = 12  # Gauss-Newton steps of the joint multi-view ICP
    joint_stability: float = 1e-3  # joint ICP keeps directions weaker than this share fixed
    sphere_radius: float | None = 5e-3
    sphere_tolerance: float = 0.1e-3
    sphere_min_points: int = 30
    sphere_match_distance: float = 2e-3


@dataclass
class PreprocessReport:
    """What each step did (counts of points; lengths in m).

    ``spheres_found`` and ``sphere_points_removed`` are per view; ``spheres_matched`` counts the
    reference spheres found by two or more views (the registration's datums), ``spheres_single``
    those only one view found (removed, not datums), and ``sphere_rms`` is the RMS distance
    between two views' placements of one sphere's centre after registration (NaN without).
    """

    input_points: list[int] = field(default_factory=list)
    spheres_found: list[int] = field(default_factory=list)
    sphere_points_removed: list[int] = field(default_factory=list)
    spheres_matched: int = 0
    spheres_single: int = 0
    sphere_rms: float = float("nan")
    outliers_removed: list[int] = field(default_factory=list)
    smoothing_mean_shift: list[float] = field(default_factory=list)
    pair_fitness: dict[str, float] = field(default_factory=dict)
    pair_rmse: dict[str, float] = field(default_factory=dict)
    pose_graph_edges: int = 0
    pose_graph_pruned: int = 0
    joint_rms: float = float("nan")
    joint_weak_directions: int = 0
    fused_points: int = 0
    downsampled_points: int = 0

    def as_dict(self) -> dict:
        return dict(self.__dict__)
