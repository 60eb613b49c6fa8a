import pytest

from amr_twin.base.registry import Registry


def test_registration_order_lookup_and_refusal():
    reg = Registry("--thing")
    reg.register("b", 2)

    @reg.register("a")
    def make_a():
        return 1

    assert reg.names() == ("b", "a")
    assert reg.get("a") is make_a and "a" in reg and len(reg) == 2
    assert reg.choices() == "b or a"
    with pytest.raises(ValueError, match=r"--thing 'c': must be one of b or a"):
        reg.get("c")
    with pytest.raises(ValueError, match="already registered"):
        reg.register("b", 3)
    reg.register("b", 3, replace=True)
    assert reg.get("b") == 3
    reg.unregister("b")
    assert reg.names() == ("a",)


@pytest.mark.parametrize("bad", ["", "Up", "a b", "x.y"])
def test_names_that_no_option_could_take_are_refused(bad):
    with pytest.raises(ValueError, match="name"):
        Registry("--thing").register(bad, 1)
