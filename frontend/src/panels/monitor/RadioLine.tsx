/** A datagram link's figures beside the planned ones (udp, serial): loss,
 * retransmissions, datagrams dropped, and the bytes/s flowing back. */
import { fixed, whole } from "../../core/numberFormat";
import { formatRate } from "../../core/plan";
import type { RadioFigures } from "../../dataSources/types";

export function RadioLine({ radio }: { radio: RadioFigures }) {
  const dropped = radio.forged + radio.replayed + radio.malformed;
  return (
    <span className="radio-figures" aria-label="Radio link">
      {" "}· {radio.transport}: loss {radio.loss === null ? "—" : fixed(radio.loss * 100, 1, " %")}
      {" "}· resent {whole(radio.retransmissions)}
      {" "}· dropped {whole(dropped)}
      {dropped > 0 && ` (${whole(radio.forged)} forged, ${whole(radio.replayed)} replayed, ${whole(radio.malformed)} malformed)`}
      {" "}· base→drone {radio.outBytesPerS === null ? "—" : formatRate(radio.outBytesPerS)}
      {" "}vs planned {radio.plannedOutBytesPerS === null ? "—" : formatRate(radio.plannedOutBytesPerS)}
    </span>
  );
}
