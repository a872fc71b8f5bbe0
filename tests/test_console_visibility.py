"""The water's visibility, a setting of the session: refused outside 2-30 m with the range in
the message (the console's own check and the API's), set and read back over HTTP with the
token, and refused without it."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from fastapi.testclient import TestClient

from app.console import VISIBILITY_MAX_M, VISIBILITY_MIN_M, ConsoleError, ConsoleSettings, Water
from app.server import create_app

TOKEN = "visibility-test-token-0123456789"
AUTH = {"Authorization": f"Bearer {TOKEN}"}


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    settings = ConsoleSettings(
        view=False, token=TOKEN, recordings_dir=tmp_path_factory.mktemp("recordings")
    )
    with TestClient(create_app(settings), base_url="http://127.0.0.1") as c:
        yield c


@pytest.mark.parametrize("bad", [VISIBILITY_MIN_M - 0.1, VISIBILITY_MAX_M + 1.0, float("nan")])
def test_visibility_out_of_range_is_refused_with_the_range(bad: float) -> None:
    water = Water()
    with pytest.raises(ConsoleError, match="between 2 and 30 m"):
        water.set_visibility_m(bad)
    assert water.set_visibility_m(VISIBILITY_MIN_M) == VISIBILITY_MIN_M


def test_visibility_over_http(client: TestClient) -> None:
    default = client.get("/api/environment/visibility").json()["visibility_m"]
    assert VISIBILITY_MIN_M <= default <= VISIBILITY_MAX_M
    r = client.put("/api/environment/visibility", json={"visibility_m": 4.5}, headers=AUTH)
    assert r.status_code == 200 and r.json() == {"visibility_m": 4.5}
    assert client.get("/api/environment/visibility").json() == {"visibility_m": 4.5}
    for bad, words in ((45.0, "less than or equal to 30"), (1.0, "greater than or equal to 2")):
        r = client.put("/api/environment/visibility", json={"visibility_m": bad}, headers=AUTH)
        assert r.status_code == 422 and words in r.text, r.text
    r = client.put("/api/environment/visibility", json={"visibility_m": 10.0})
    assert r.status_code == 401
    assert client.get("/api/environment/visibility").json() == {"visibility_m": 4.5}
