"""The stepwise selection rule (diagnose/selection/rule.py) on tables of chi2 values, so each
clause of the rule is checked on its own: the misfit test, the IC and "explains little"
tests, and the pair step for two effects that each hide the other."""

import math

from iwan_element.diagnose.selection.rule import stepwise_select

N_EFF = 400.0


def _candidate(table):
    """fit_candidate from a table {stack (frozenset of names): chi2}; one parameter each."""

    def fit(cur, name):
        names = tuple(cur["names"]) + (name,)
        return {"names": names, "chi2": table[frozenset(names)], "q": 1, "state": names}

    return fit


def _run(table, base_chi2, **kw):
    base = {"names": (), "chi2": base_chi2, "q": 5, "state": ()}
    return stepwise_select(_candidate(table), ("a", "b", "c"), base, tau=1.0, n_eff=N_EFF, **kw)


def _table(a, b, c, ab, ac=None, bc=None):
    f = frozenset
    return {f("a"): a, f("b"): b, f("c"): c, f("ab"): ab, f("ac"): ac or a, f("bc"): bc or b}


def test_noise_level_misfit_names_nothing_even_with_a_large_pair_gain():
    # chi2 at its expectation: the misfit test stops before any step (no pair is tried)
    sel = _run(_table(380.0, 385.0, 390.0, 10.0), N_EFF - 5)
    assert sel.named == [] and sel.steps == []


def test_single_effect_named_greedily_and_pair_not_needed():
    sel = _run(_table(1000.0, 4000.0, 4100.0, 950.0), 5000.0)
    assert sel.named[0] == "a"
    assert all(r.get("verdict") != "NAMED (pair)" for st in sel.steps for r in st["rows"])


def test_pair_named_when_each_alone_explains_little():
    excess = 10000.0 - (N_EFF - 5)
    a, b = 10000.0 - 0.20 * excess, 10000.0 - 0.15 * excess  # 20 % and 15 %
    sel = _run(_table(a, b, 9990.0, 10000.0 - 0.6 * excess), 10000.0)
    assert set(sel.named) == {"a", "b"} and len(sel.named) == 2
    assert sel.final["q"] == 7
    assert sel.steps[-1]["rows"][0]["verdict"] == "NAMED (pair)"
    # not without the pair step
    assert _run(_table(a, b, 9990.0, 10000.0 - 0.6 * excess), 10000.0, pairs=False).named == []
    # nor when max_effects leaves room for one effect only
    assert _run(_table(a, b, 9990.0, 10000.0 - 0.6 * excess), 10000.0, max_effects=1).named == []


def test_pair_whose_partner_does_not_earn_its_parameter_is_not_named():
    # excess 150: "a" removes 22 %, the pair 25.3 % (enough, and it lowers the IC with both
    # parameters counted), but "b" adds less than one parameter's penalty ln(n_eff) on top
    # of "a": the pair is not named
    base = (N_EFF - 5) + 150.0
    a, b, ab = base - 33.0, base - 10.0, base - 38.0
    assert 38.0 - 33.0 < math.log(N_EFF) < 38.0 / 2
    sel = _run(_table(a, b, base - 1.0, ab), base)
    assert sel.named == []
    assert [r["verdict"] for r in sel.steps[-1]["rows"]] == ["pair explains little"]
    # with "b" earning its parameter, the same pair is named
    assert set(_run(_table(a, b, base - 1.0, base - 45.0), base).named) == {"a", "b"}


def test_pair_partner_need_not_be_the_runner_up_alone():
    # "a" leads (20 %); "b" alone explains more (15 %) than "c" (5 %), but "a" hides "c":
    # a + c explains 60 % while a + b adds nothing to "a". The best single is tried with every
    # partner that lowers the IC, so "a" + "c" is named; the old rule (the two best singles
    # only) would try a + b and b + a and name nothing.
    excess = 10000.0 - (N_EFF - 5)
    a, b, c = (10000.0 - f * excess for f in (0.20, 0.15, 0.05))
    sel = _run(_table(a, b, c, a, ac=10000.0 - 0.6 * excess, bc=b), 10000.0)
    assert set(sel.named) == {"a", "c"}
    tried = {r["name"]: r["verdict"] for r in sel.steps[-1]["rows"]}
    assert tried == {"a + b": "pair explains little", "a + c": "NAMED (pair)"}


def test_pair_partner_that_does_not_lower_the_ic_alone_is_not_tried():
    # "c" alone gains less than one parameter's penalty: it is not a partner, however good
    # the pair would be (the pair step costs a fit per partner; a partner must show itself)
    excess = 10000.0 - (N_EFF - 5)
    a, b = 10000.0 - 0.20 * excess, 10000.0 - 0.15 * excess
    c = 10000.0 - 0.5 * math.log(N_EFF)
    sel = _run(_table(a, b, c, a, ac=10000.0 - 0.6 * excess, bc=b), 10000.0)
    assert sel.named == []
    assert [r["name"] for r in sel.steps[-1]["rows"]] == ["a + b"]


def _ordered(table):
    """fit_candidate from a table {stack (tuple, in fit order): chi2}: the second member
    fitted on top of the first may land elsewhere than the other way round."""

    def fit(cur, name):
        names = tuple(cur["names"]) + (name,)
        key = names if names in table else frozenset(names)
        return {"names": names, "chi2": table[key], "q": 1, "state": names}

    return fit


def test_a_pair_is_listed_once_in_one_order_with_its_better_fit():
    # both orders of b + a qualify, with different chi2 (the fit path differs): one row,
    # titled "a + b" (sorted), the better order's chi2, NAMED
    excess = 10000.0 - (N_EFF - 5)
    a, b = (10000.0 - f * excess for f in (0.20, 0.15))
    c = 10000.0 - 0.5 * math.log(N_EFF)  # no partner (does not lower the IC alone)
    table = {
        **_table(a, b, c, 0.0),
        ("a", "b"): 10000.0 - 0.6 * excess,
        ("b", "a"): 10000.0 - 0.7 * excess,
    }
    base = {"names": (), "chi2": 10000.0, "q": 5, "state": ()}
    sel = stepwise_select(_ordered(table), ("a", "b", "c"), base, tau=1.0, n_eff=N_EFF)
    rows = sel.steps[-1]["rows"]
    assert [r["name"] for r in rows] == ["a + b"]
    assert rows[0]["chi2"] == table[("b", "a")] and rows[0]["verdict"] == "NAMED (pair)"
    assert sel.final["chi2"] == table[("b", "a")] and set(sel.named) == {"a", "b"}


def test_only_the_named_pair_is_marked_named():
    # a + b and a + c both pass every test; a + c is better: it alone is NAMED
    excess = 10000.0 - (N_EFF - 5)
    a, b, c = (10000.0 - f * excess for f in (0.20, 0.15, 0.10))
    t = _table(a, b, c, 10000.0 - 0.6 * excess, ac=10000.0 - 0.7 * excess)
    sel = _run(t, 10000.0)
    verdicts = {r["name"]: r["verdict"] for r in sel.steps[-1]["rows"]}
    assert verdicts == {
        "a + b": "qualifies, less good than the named pair",
        "a + c": "NAMED (pair)",
    }
    assert set(sel.named) == {"a", "c"}
