"""Discovery's candidates are the effect catalog's effects: names, parameters, defaults and units
from the catalog (the manifest), discovery's own fitting settings beside them."""

from __future__ import annotations

import pytest

from gsfric import models
from gsfric.discovery import candidates as cand
from gsfric.discovery.lackfit import CATALOG_EQUIVALENT
from gsfric.errors import GsfricError
from gsfric.platform.catalog import describe

SPEC_NAMES = {"stribeck", "seal_friction", "quadratic_drag", "stroke_friction", "payload_offset",
              "sensor_bias", "joint_friction_coupling", "leg_weight", "force_scale",
              "time_offset", "bushing_friction"}
"""The effect names that the product's contract fixes for discovery."""


def test_candidate_names_are_the_catalogs_effect_names():
    """One candidate per catalog effect, in the catalog's order; the contract's names among
    them (a catalog effect without a candidate, or a renamed one, fails here)."""
    assert cand.CANDIDATE_NAMES == tuple(e["name"] for e in describe())
    assert SPEC_NAMES <= set(cand.CANDIDATE_NAMES)


def test_each_candidates_parameters_are_the_catalogs():
    """Parameters, defaults and units are the catalog's; each parameter is fitted, held (set
    from the platform) or refined, exactly once, and the fitted ones keep the catalog's order."""
    entries = {e["name"]: e for e in describe()}
    for c in cand.CANDIDATES:
        params = entries[c.name]["parameters"]
        assert dict(c.parameters) == {p["name"]: p["default"] for p in params}, c.name
        assert dict(c.units) == {p["name"]: p["unit"] for p in params}, c.name
        assert sorted(c.fitted + c.held + c.refined) == sorted(c.parameters), c.name
        order = list(c.parameters)
        assert [order.index(p) for p in c.fitted] == sorted(order.index(p) for p in c.fitted)
        assert len(c.lower) == len(c.upper) == len(c.fitted), c.name
        assert all(lo < hi for lo, hi in zip(c.lower, c.upper)), c.name


def test_fixed_values_are_exactly_the_held_parameters():
    """``fixed`` sets the held parameters and nothing else (a held parameter left unset would
    keep no value in the fit)."""
    platform = models.reference_platform("paper")
    for c in cand.CANDIDATES:
        assert set(c.fixed(platform, {})) == set(c.held), c.name


def test_a_setting_for_a_parameter_the_catalog_lacks_is_refused():
    with pytest.raises(GsfricError, match=r"candidate seal_friction: speed is not a parameter "
                                          r"of the catalog's seal_friction \(force\)"):
        cand.Candidate(name="seal_friction", parameters={"force": 0.0}, units={"force": "N"},
                       signature="signature", bounds_of={"speed": (0.0, 1.0)})


def test_fitting_settings_must_cover_the_catalog(monkeypatch):
    fitting = dict(cand.FITTING)
    del fitting["leg_weight"]
    fitting["leg_mass"] = {"signature": "load-like"}
    monkeypatch.setattr(cand, "FITTING", fitting)
    with pytest.raises(GsfricError, match=r"no settings for \['leg_weight'\], settings for "
                                          r"unknown effects \['leg_mass'\]"):
        cand._candidates()


def test_structures_equivalent_to_an_effect_name_a_candidate():
    """A lack-of-fit structure that equals a catalog effect names that candidate (a misspelt
    name would let the structure be reported as outside the catalog)."""
    assert set(CATALOG_EQUIVALENT.values()) <= set(cand.CANDIDATE_NAMES)


def test_bushing_friction_is_fitted_at_the_rigs_own_bushing_spacing():
    """The effect's force is coefficient / spacing times the bending moment: it is fitted at
    the platform's ``[effects]`` spacing when there is one, else at the rig's bushings'
    (``[friction] bushing_spacing``), so that its coefficient is the rig's."""
    bushing = next(c for c in cand.CANDIDATES if c.name == "bushing_friction")
    wide = models.reference_platform().with_friction(bushing_spacing=1.0)
    assert bushing.fixed(wide, {}) == {"spacing": 1.0}
    own = wide.with_effect("bushing_friction", coefficient=0.0, spacing=0.3)
    assert bushing.fixed(own, {}) == {"spacing": 0.3}
