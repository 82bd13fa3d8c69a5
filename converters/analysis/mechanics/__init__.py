"""The mechanical module's studies, beside the engine they run on: sliding bifurcations of the dry-friction
oscillator, the two blocks on a belt, the cam-follower's impacts and chattering, and the cross-checks of the event
method against Moreau-Jean and closed forms.

Nothing here integrates or shoots: every run is ``simulate`` or a method's period map, every orbit the
continuation's (the mechanical module reuses the core and the bifurcation tools). What the report shows of them,
with the seed's settings and the pass/fail thresholds, is ``validation.mechanics``.
"""
from .friction import (Basins, DegenerateSwitching, SlidingStudy, basins, degenerate_portraits, degenerate_switching,
                       friction_agreement, friction_diagram, resolution_check, sliding_study, stick_intervals)
from .impacts import (CornerImpact, ball_check, cam_checks, cam_continuation, cam_family, chattering_orbit,
                      chattering_table, chattering_transition, chattering_windows, corner_impact, corner_impacts,
                      impact_angles, impact_phase_diagram, incomplete_across, incomplete_orbit, least_clearance,
                      locate_corner, locate_grazing, ride_left)
from .orbits import CONTINUATION, mechanical_path, orbit_period
from .two_block import lyapunov_of_flow, two_block_diagram, two_block_regime, two_block_regimes

__all__ = ["Basins", "DegenerateSwitching", "SlidingStudy", "basins", "degenerate_portraits", "degenerate_switching",
           "friction_agreement", "friction_diagram", "resolution_check", "sliding_study", "stick_intervals",
           "CornerImpact", "ball_check", "cam_checks", "cam_continuation", "cam_family", "chattering_orbit",
           "chattering_table", "chattering_transition", "chattering_windows", "corner_impact", "corner_impacts",
           "impact_angles", "impact_phase_diagram", "incomplete_across", "incomplete_orbit", "least_clearance",
           "locate_corner", "locate_grazing", "ride_left", "CONTINUATION", "mechanical_path", "orbit_period",
           "lyapunov_of_flow", "two_block_diagram", "two_block_regime", "two_block_regimes"]
