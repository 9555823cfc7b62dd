/**
 * A small highlighter for the .modd text (keywords, strings, numbers,
 * comments) as a CodeMirror stream language. Highlighting only: parsing and
 * errors come from the backend's parser, the one grammar.
 */
import { StreamLanguage } from "@codemirror/language";
import { AggregationValues } from "../../core/model.gen";

const KEYWORDS = new RegExp(`^(DataCollector|Drone|Sensors|Sensor|measures|PubBroker|SubBroker|Publishers|Publisher|Subscriptions|Subscriber|Link|${AggregationValues.join("|")})\\b`);

export const moddLanguage = StreamLanguage.define<{ inComment: boolean }>({
  startState: () => ({ inComment: false }),
  token(stream, state) {
    if (state.inComment) {
      if (stream.match(/.*?\*\//)) state.inComment = false;
      else stream.skipToEnd();
      return "comment";
    }
    if (stream.eatSpace()) return null;
    if (stream.match("//")) { stream.skipToEnd(); return "comment"; }
    if (stream.match("/*")) { state.inComment = true; return "comment"; }
    if (stream.match(/^"(?:[^"\\]|\\.)*"?/)) return "string";
    if (stream.match(/^\d*\.?\d+|^\d+\./)) return "number";
    if (stream.match(KEYWORDS)) return "keyword";
    if (stream.match(/^[A-Za-z_][A-Za-z0-9_]*/)) return "variableName";
    stream.next();
    return "punctuation";
  },
});
