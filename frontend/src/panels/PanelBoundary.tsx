/**
 * Every panel renders inside one of these: a failure stays in the panel (with
 * its message and a retry), and a lazy panel shows a loading state.
 */
import { Component, Suspense, type ReactNode } from "react";

interface Props { title: string; children: ReactNode }
interface State { error: Error | null }

export class PanelBoundary extends Component<Props, State> {
  state: State = { error: null };

  static getDerivedStateFromError(error: Error): State {
    return { error };
  }

  render() {
    if (this.state.error) {
      return (
        <div className="panel-error" role="alert">
          <strong>The {this.props.title} panel failed.</strong>
          <pre>{this.state.error.message}</pre>
          <button onClick={() => this.setState({ error: null })}>Retry</button>
        </div>
      );
    }
    return <Suspense fallback={<div className="panel-loading" role="status">Loading {this.props.title}…</div>}>{this.props.children}</Suspense>;
  }
}
