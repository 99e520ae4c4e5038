"""tools/start_check_bench.py: which rule keeps the clearly worse heading."""
from tool_module import load_tool


def _tool():
    return load_tool("start_check_bench")


def _hyp(unexplained, energy, within):
    return {"unexplained": unexplained, "energy": energy, "within_10cm": within}


def test_each_rule_counts_the_starts_where_it_kept_the_clearly_worse_heading():
    tool = _tool()
    results = [
        # the turned twin is right; the share leads by 4 % (under the 10 % margin), the energy by 3 %
        {"name": "a", "initial": _hyp(0.25, 1.00, 0.2), "turned": _hyp(0.24, 0.97, 0.9)},
        # the initial heading is right; the energy prefers the turned one
        {"name": "b", "initial": _hyp(0.20, 1.00, 0.8), "turned": _hyp(0.30, 0.90, 0.2)},
        # both about as good: never counted
        {"name": "c", "initial": _hyp(0.20, 1.00, 0.5), "turned": _hyp(0.10, 0.90, 0.45)},
        {"name": "d", "initial": _hyp(0.20, 1.00, 0.5), "turned": None},
    ]
    wrong = tool.rule_failures(results, clear=0.2)
    assert wrong["unexplained, margin 0.10"] == ["a"]
    assert wrong["unexplained, margin 0"] == []
    assert wrong["energy, margin 0"] == ["b"]
    assert tool.rule_failures(results, clear=0.8)["unexplained, margin 0.10"] == []
