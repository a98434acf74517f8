"""The HTTP service's access rules (issue 22, item 3): token file, bind address, bearer
check (401 without, 403 for a read-only token acknowledging), security headers on every
response."""

from __future__ import annotations

import re

import pytest
from fastapi.testclient import TestClient

from steamtwin.web.access import (
    SECURITY_HEADERS,
    AccessError,
    AccessPolicy,
    check_bind,
    is_loopback,
    load_tokens,
)
from steamtwin.web.app import create_app

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")

READ = "r" * 40
ACK = "a" * 40


def _token_file(tmp_path, text: str):
    path = tmp_path / "tokens.toml"
    path.write_text(text)
    return path


@pytest.fixture
def policy(tmp_path) -> AccessPolicy:
    return load_tokens(_token_file(
        tmp_path, f'[[tokens]]\nname = "viewer"\nrole = "read"\ntoken = "{READ}"\n'
                  f'[[tokens]]\nname = "shift-lead"\nrole = "ack"\ntoken = "{ACK}"\n'))


def test_token_file_mistakes_name_file_and_entry(tmp_path):
    with pytest.raises(AccessError, match=r"tokens\[0\].role = 'admin'"):
        load_tokens(_token_file(tmp_path, f'[[tokens]]\nname = "x"\nrole = "admin"\n'
                                          f'token = "{READ}"\n'))
    with pytest.raises(AccessError, match=r"tokens\[0\].token: expected at least 32"):
        load_tokens(_token_file(tmp_path, '[[tokens]]\nname = "x"\nrole = "read"\n'
                                          'token = "short"\n'))
    with pytest.raises(AccessError, match=r"tokens\[1\].token is used twice"):
        load_tokens(_token_file(tmp_path, "".join(
            f'[[tokens]]\nname = "{n}"\nrole = "read"\ntoken = "{READ}"\n' for n in "ab")))
    with pytest.raises(AccessError, match=r"missing\.toml: cannot read the token file"):
        load_tokens(tmp_path / "missing.toml")
    binary = tmp_path / "binary.toml"
    binary.write_bytes(bytes(range(256)))
    with pytest.raises(AccessError, match=r"binary.toml: not UTF-8 text \(byte 0x80"):
        load_tokens(binary)


def test_bearer_tokens_are_matched_to_their_holder(policy):
    assert policy.authenticate(f"Bearer {ACK}").name == "shift-lead"
    assert policy.authenticate(f"bearer {READ}").role == "read"
    for wrong in (None, "", READ, f"Basic {READ}", f"Bearer {READ}x", "Bearer "):
        assert policy.authenticate(wrong) is None


def test_a_non_loopback_bind_needs_tokens(policy):
    for host in ("127.0.0.1", "127.0.0.2", "::1", "localhost"):
        assert is_loopback(host)
        check_bind(host, AccessPolicy())
    for host in ("0.0.0.0", "10.0.0.5", "::", "plant-gw.example"):
        assert not is_loopback(host)
        with pytest.raises(AccessError, match="needs --token-file"):
            check_bind(host, AccessPolicy())
        check_bind(host, policy)


def test_every_request_needs_a_valid_token_and_acknowledging_an_ack_token(filled_db, policy):
    with TestClient(create_app(filled_db, access=policy)) as client:
        for headers in ({}, {"Authorization": "Bearer " + "x" * 40}):
            refused = client.get("/api/units", headers=headers)
            assert refused.status_code == 401
            assert refused.headers["www-authenticate"].startswith("Bearer")
            assert "bearer token" in refused.json()["error"]
        read = {"Authorization": f"Bearer {READ}"}
        assert [u["name"] for u in client.get("/api/units", headers=read).json()] == [
            "unit1", "unit2"]
        denied = client.post("/api/alarms/1/acknowledge", json={}, headers=read)
        assert denied.status_code == 403 and "read-only" in denied.json()["error"]
        assert client.get("/api/alarms/1", headers=read).json()["acknowledged_at"] is None
        done = client.post("/api/alarms/1/acknowledge", json={"by": "someone else"},
                           headers={"Authorization": f"Bearer {ACK}"})
        assert done.status_code == 200
        assert done.json()["acknowledged_by"] == "shift-lead"  # the token's holder, not the body
        again = client.post("/api/alarms/1/acknowledge", json={},
                            headers={"Authorization": f"Bearer {ACK}"})
        assert again.status_code == 409 and "shift-lead" in again.json()["error"]


def test_security_headers_on_every_response(filled_db, policy):
    with TestClient(create_app(filled_db, access=policy)) as client:
        auth = {"Authorization": f"Bearer {READ}"}
        responses = [client.get("/api/units", headers=auth), client.get("/", headers=auth),
                     client.get("/docs", headers=auth), client.get("/nowhere", headers=auth),
                     client.get("/static/style.css", headers=auth), client.get("/api/units")]
        assert [r.status_code for r in responses] == [200, 200, 200, 404, 200, 401]
        for response in responses:
            for name, value in SECURITY_HEADERS:
                assert response.headers[name.decode()] == value.decode()
        policy_text = responses[0].headers["content-security-policy"]
        assert "default-src 'self'" in policy_text and "unsafe-inline" not in policy_text
        for page in responses[1:3]:  # the pages run no inline script and load nothing remote
            assert re.findall(r"<script(?![^>]*\bsrc=\"/)", page.text) == []
            assert "http://" not in page.text.replace("http://www.w3.org", "")
