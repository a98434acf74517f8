"""The OPC UA source against a server that demands Basic256Sha256 / SignAndEncrypt and a user
name (issue 21, "Security"): certificates and a password get data; a wrong password or a client
without a certificate get none, and say why. A real asyncua server on 127.0.0.1."""

from __future__ import annotations

import asyncio
from datetime import UTC, datetime, timedelta

import pytest
from asyncua import Server, ua
from asyncua.crypto.cert_gen import setup_self_signed_certificate
from asyncua.crypto.permission_rules import User, UserRole
from cryptography.x509.oid import ExtendedKeyUsageOID
from ports import free_port

from steamtwin.dcs.plant import plant_tag_map
from steamtwin.live.sources import OpcUaSecurity, OpcUaSource

pytestmark = pytest.mark.slow  # 19 s of the full suite (2026-11-27): not in the quick loop

CLIENT_URI = "urn:freeopcua:client"  # asyncua's client application URI, in its certificate


class _Passwords:
    """The server's user check: one user name and password."""

    def get_user(self, iserver, username=None, password=None, certificate=None):
        if username == "twin" and password == "s3cret":
            return User(role=UserRole.User)
        return None



@pytest.fixture(scope="module")
def certificates(tmp_path_factory):
    folder = tmp_path_factory.mktemp("pki")

    async def make():
        for name, uri, use in (("server", "urn:steamtwin:test-server",
                                ExtendedKeyUsageOID.SERVER_AUTH),
                               ("client", CLIENT_URI, ExtendedKeyUsageOID.CLIENT_AUTH)):
            await setup_self_signed_certificate(folder / f"{name}.pem", folder / f"{name}.der",
                                                uri, "localhost", [use],
                                                {"commonName": f"steamtwin test {name}"})

    asyncio.run(make())
    return folder


def _run(certificates, security: OpcUaSecurity) -> tuple[int, list[str]]:
    port = free_port()
    endpoint = f"opc.tcp://127.0.0.1:{port}/secure/"
    tag_map = plant_tag_map()
    import dataclasses

    spec = dataclasses.replace(tag_map.signals["main_steam_pressure"],
                               node_id="nsu=urn:secure;s=P")
    mapped = dataclasses.replace(tag_map, signals={"main_steam_pressure": spec})

    async def scenario():
        server = Server(user_manager=_Passwords())
        await server.init()
        server.set_endpoint(endpoint)
        server.set_security_policy([ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt])
        server.set_security_IDs(["Username"])
        await server.load_certificate(str(certificates / "server.der"))
        await server.load_private_key(str(certificates / "server.pem"))
        index = await server.register_namespace("urn:secure")
        variable = await server.nodes.objects.add_variable(
            ua.NodeId("P", index), "P", ua.Variant(0.0, ua.VariantType.Double))
        await server.write_attribute_value(variable.nodeid, ua.DataValue(
            Value=ua.Variant(0.0, ua.VariantType.Double),
            StatusCode=ua.StatusCode(ua.StatusCodes.BadWaitingForInitialData)))
        await server.start()
        source = OpcUaSource(endpoint, mapped, security, reconnect_s=0.5, settle_s=0.5)
        blocks = []

        async def consume():
            async for block in source.blocks():
                blocks.append(block)

        task = asyncio.create_task(consume())
        await asyncio.sleep(2.0)
        base = datetime(2026, 3, 1, tzinfo=UTC)
        for k in range(5):
            await server.write_attribute_value(variable.nodeid, ua.DataValue(
                Value=ua.Variant(16.0 + k, ua.VariantType.Double),
                SourceTimestamp=base + timedelta(seconds=k)))
            await asyncio.sleep(0.05)
        await asyncio.sleep(1.5)
        source.close()
        await asyncio.wait_for(task, timeout=20)
        await server.stop()
        return blocks

    blocks = asyncio.run(scenario())
    samples = sum(len(block.frame) for block in blocks)
    messages = [finding.message for block in blocks for finding in block.findings]
    return samples, messages


def test_certificates_and_a_password_get_the_data(certificates):
    security = OpcUaSecurity(certificate=certificates / "client.der",
                             private_key=certificates / "client.pem", user="twin",
                             password="s3cret")
    samples, _ = _run(certificates, security)
    assert samples == 5


def test_a_wrong_password_or_no_certificate_gets_nothing(certificates):
    wrong = OpcUaSecurity(certificate=certificates / "client.der",
                          private_key=certificates / "client.pem", user="twin",
                          password="guess")
    samples, messages = _run(certificates, wrong)
    assert samples == 0 and any("cannot connect" in m for m in messages)
    insecure = OpcUaSecurity(allow_insecure=True)
    samples, messages = _run(certificates, insecure)
    assert samples == 0 and any("cannot connect" in m for m in messages)
