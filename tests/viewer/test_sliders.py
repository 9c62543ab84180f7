"""Sliders the server sets: re-created in place once a browser has changed them
(the real-browser check of the dropped paste is in test_browser.py)."""

from orientviz.viewer.sliders import Sliders


def _from_browser(handle, value):
    """What viser does when a browser sends a new value: store it, call the callbacks
    with the client's id."""
    from viser import GuiEvent

    handle._impl.value = value
    for cb in list(handle._impl.update_cb):
        cb(GuiEvent(client=None, client_id=7, target=handle))


def test_a_slider_changed_in_a_browser_is_recreated_in_place_when_the_server_sets_it(server):
    gui, handles, seen = server.gui, {}, []
    sliders = Sliders(gui, handles)
    with gui.add_folder("dials") as folder:
        gui.add_markdown("before")
        sliders.add("x", folder, "X0 [m]", -10.0, 10.0, 0.1, 0.0, hint="the hint")
        gui.add_markdown("after")
    sliders.on_update("x", lambda e: seen.append(e.target.value))
    first = handles["x"]

    sliders.set("x", 2.0)  # untouched: viser's own assignment, callbacks as viser calls them
    assert handles["x"] is first and first.value == 2.0 and seen == [2.0]
    assert not sliders.touched("x") and sliders.recreated == 0

    _from_browser(first, 0.3)
    assert sliders.touched("x") and seen == [2.0, 0.3]
    first.disabled = True
    sliders.set("x", 0.3)  # the value it has: nothing to do
    assert handles["x"] is first and sliders.recreated == 0

    sliders.set("x", 0.0)
    new = handles["x"]
    assert new is not first and first._impl.removed and sliders.recreated == 1
    assert new.value == 0.0 and seen == [2.0, 0.3, 0.0]
    # same place and look: folder, order, label, range, step, hint, state
    assert new._impl.parent_container_id == folder._impl.uuid
    assert new.order == first.order
    assert (new.label, new.min, new.max, new.step) == ("X0 [m]", -10.0, 10.0, 0.1)
    assert new.hint == "the hint" and new.disabled and new.visible
    assert not sliders.touched("x")

    _from_browser(new, 0.5)  # the new slider's callbacks are the old ones
    assert seen[-1] == 0.5 and sliders.touched("x")
    sliders.set("x", -1.0)
    assert handles["x"] is not new and handles["x"].value == -1.0 and sliders.recreated == 2


def test_an_integer_slider_stays_integer_when_recreated(server):
    gui, handles = server.gui, {}
    sliders = Sliders(gui, handles)
    with gui.add_folder("scrubber") as folder:
        sliders.add("it", folder, "iteration", 0, 1, 1, 0)
    handles["it"].max = 4
    _from_browser(handles["it"], 1)
    sliders.set("it", 3.0)
    assert handles["it"].value == 3 and type(handles["it"].value) is int
    assert handles["it"].max == 4 and sliders.recreated == 1
