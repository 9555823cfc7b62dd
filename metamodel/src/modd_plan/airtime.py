"""Air time of one radio packet, per kind of radio (docs/planning.md,
"Radio profiles"). Pure functions of the packet's payload and the radio's
settings; :mod:`modd_plan.radio` sums them over a plan's packets.

* LoRa: Semtech's time-on-air formula (SX1276/77/78/79 datasheet, section
  4.1.1.7; AN1200.13, "LoRa Modem Designer's Guide").
* SiK/RFD900-class serial radios: the payload plus a per-packet overhead
  (:data:`SIK_OVERHEAD_BYTES`), at the air rate, doubled with Golay ECC.
* Wi-Fi (802.11 OFDM): a fixed per-packet exchange (:data:`WIFI_OVERHEAD_S`)
  plus the MAC frame at the PHY rate.
"""

from __future__ import annotations

from math import ceil

#: SiK's radio packet around the payload: preamble (5 B), sync word (2 B),
#: header (4 B: length, network id, flags), CRC (2 B); an estimate of the
#: firmware's Si1000 packet handler settings, not a measured figure
SIK_OVERHEAD_BYTES = 13
#: 802.11a/g OFDM, one unicast frame with its ACK and no contention:
#: DIFS 34 us + mean backoff 7.5 slots x 9 us + PLCP preamble and header
#: 20 us + SIFS 16 us + ACK 44 us (at 6 Mbit/s basic rate, 14 B + preamble)
WIFI_OVERHEAD_S = (34 + 67.5 + 20 + 16 + 44) / 1e6
#: MAC header (24 B) + LLC/SNAP (8 B) + FCS (4 B) around the payload
WIFI_MAC_BYTES = 36
#: LoRa's symbol duration above which low-data-rate optimisation is mandated
LDRO_SYMBOL_S = 0.016


def lora_symbol_s(sf: int, bandwidth_hz: int) -> float:
    """One LoRa symbol: 2^SF / BW seconds.

    >>> lora_symbol_s(7, 125_000)
    0.001024
    """
    return float(2**sf) / bandwidth_hz


def lora_time_on_air(
    payload: int,
    sf: int,
    bandwidth_hz: int,
    coding_rate: int = 5,
    preamble: int = 8,
    explicit_header: bool = True,
    crc: bool = True,
    low_data_rate: bool | None = None,
) -> float:
    """Seconds on air of one LoRa packet of ``payload`` bytes; ``coding_rate``
    is the denominator of 4/5..4/8; ``low_data_rate`` None: on when a symbol
    lasts more than 16 ms (the datasheet's rule).

    >>> round(lora_time_on_air(20, 7, 125_000) * 1000, 3)
    56.576
    """
    t_sym = lora_symbol_s(sf, bandwidth_hz)
    de = (t_sym > LDRO_SYMBOL_S) if low_data_rate is None else low_data_rate
    ih = 0 if explicit_header else 1
    numerator = 8 * payload - 4 * sf + 28 + 16 * int(crc) - 20 * ih
    symbols = 8 + max(ceil(numerator / (4 * (sf - 2 * int(de)))) * coding_rate, 0)
    return (preamble + 4.25) * t_sym + symbols * t_sym


def sik_time_on_air(payload: int, air_rate_bps: int, ecc: bool = False) -> float:
    """Seconds on air of one SiK radio packet of ``payload`` bytes.

    >>> sik_time_on_air(87, 64_000)
    0.0125
    """
    bits = (payload + SIK_OVERHEAD_BYTES) * 8
    return bits * (2 if ecc else 1) / air_rate_bps


def wifi_time_on_air(payload: int, phy_rate_bps: int) -> float:
    """Seconds on air of one Wi-Fi frame of ``payload`` bytes (IP packet).

    >>> round(wifi_time_on_air(1464, 24_000_000) * 1e6, 1)
    681.5
    """
    return WIFI_OVERHEAD_S + (payload + WIFI_MAC_BYTES) * 8 / phy_rate_bps
