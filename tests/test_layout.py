"""Every vector layout (lightcraft_opt/layout/) names each entry once, and the layouts built
from one another agree with their sources.

References: invariants of the layouts. A name picks one entry (docs/architecture.md#rule-8),
so within a layout every slot name and every ``slot[component]`` signal name is unique, and
every layout has a name of its own (errors name the layout: "the state holds ..."). A slot a
layout shares with another (the director's state with Ψ's, the coning model's with the
error state and the map input) has that slot's unit and frame.
"""

from __future__ import annotations

import itertools

import pytest
from support.models import table1_flight5

from lightcraft_opt import layout
from lightcraft_opt.layout import (
    CONING_ERROR_STATE,
    DIRECTOR_INPUT,
    DIRECTOR_OUTPUT,
    DIRECTOR_STAGE,
    DIRECTOR_STATE,
    DIRECTOR_TERMINAL_OUTPUT,
    ERROR_STATE,
    REDUCED_STATE,
    RcsProfile,
    VectorLayout,
    coning_input_layout,
    input_layout,
    map_input_layout,
    substep_input_layout,
)
from lightcraft_opt.linear.signal_names import entry_names

#: The fixed layouts: every VectorLayout the layout package exports.
FIXED = {name: v for name, v in vars(layout).items() if isinstance(v, VectorLayout)}


def _built() -> list[VectorLayout]:
    """The layouts built for a craft: every RCS profile, with and without a carrier."""
    out: list[VectorLayout] = []
    for n, carrier in itertools.product((0, 1, 4), (False, True)):
        out.append(input_layout(n, carrier))
        for profile in RcsProfile:
            if n or profile is RcsProfile.HOLD:
                out.append(substep_input_layout(n, carrier, profile))
                m = 3 if profile is RcsProfile.SUBINTERVALS else 1
                out.append(map_input_layout(n, carrier, profile, m))
        if n:
            out.append(coning_input_layout(n))
    return out


def test_the_fixed_layouts_are_all_found() -> None:
    """Every upper-case name the package exports is a layout or a frame's component names."""
    components = {"ENU", "B123", "EAST_NORTH"}
    constants = {name for name in layout.__all__ if name.isupper()}
    assert set(FIXED) == constants - components
    assert {"STATE", "REDUCED_STATE", "CONING_ERROR_STATE", "DIRECTOR_INPUT"} <= set(FIXED)


@pytest.mark.parametrize("lay", [*FIXED.values(), *_built()], ids=repr)
def test_every_layout_names_each_entry_once(lay: VectorLayout) -> None:
    names = entry_names(lay)
    assert len(set(lay.names)) == len(lay.names)
    assert len(set(names)) == len(names) == lay.size
    assert len(set(lay.labels())) == lay.size
    assert all(s.size >= 1 for s in lay.slots)


def test_every_fixed_layout_has_a_name_of_its_own() -> None:
    names = [lay.name for lay in FIXED.values()]
    assert len(set(names)) == len(names), names


def test_the_coning_model_reads_error_state_and_map_input_slots() -> None:
    """CONING_ERROR_STATE's entries are ERROR_STATE entries with the same unit and frame;
    the coning input's slots are the phase-locked map input's."""
    for s in CONING_ERROR_STATE.slots:
        source = ERROR_STATE.slot(s.name)
        assert (s.unit, s.frame) == (source.unit, source.frame)
        assert set(s.components) <= set(source.components)
    assert set(entry_names(CONING_ERROR_STATE)) <= set(entry_names(ERROR_STATE))
    n = 4
    full = map_input_layout(n, False, RcsProfile.PHASE_LOCKED)
    for s in coning_input_layout(n).slots:
        source = full.slot(s.name)
        assert (s.size, s.unit, s.frame, s.components) == (
            source.size,
            source.unit,
            source.frame,
            source.components,
        )


def test_the_director_layouts_are_built_from_psi_state_and_its_own_input() -> None:
    """The QP's states are the head of Ψ's state, slot for slot (the director slices z's
    first DIRECTOR_STATE.size entries); a stage's variables are the states then the inputs;
    every input is also an output, and the terminal outputs are stage outputs."""
    head = REDUCED_STATE.slots[: len(DIRECTOR_STATE.slots)]
    assert DIRECTOR_STATE.slots == head
    stage = [(s.name, s.size, s.unit, s.frame) for s in DIRECTOR_STAGE.slots]
    parts = [*DIRECTOR_STATE.slots, *DIRECTOR_INPUT.slots]
    assert stage == [(s.name, s.size, s.unit, s.frame) for s in parts]
    assert DIRECTOR_STAGE.size == DIRECTOR_STATE.size + DIRECTOR_INPUT.size
    for lay in (DIRECTOR_INPUT, DIRECTOR_TERMINAL_OUTPUT):
        for s in lay.slots:
            out = DIRECTOR_OUTPUT.slot(s.name)
            assert (s.size, s.unit, s.frame, s.components) == (
                out.size,
                out.unit,
                out.frame,
                out.components,
            )


def test_thruster_count_is_the_rcs_slot_size() -> None:
    """Craft.thruster_count sizes the RCS slots: 0 without an RCS (no slot)."""
    craft = table1_flight5().craft
    assert craft.rcs is None and craft.thruster_count == 0
    assert "rcs_thrust" not in map_input_layout(craft.thruster_count, craft.has_carrier)
