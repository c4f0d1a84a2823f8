// macrofacet for Mitsuba 3 — what a Mitsuba object reports through traverse(): the parameters
// and nested objects that mi.traverse shows, by name. The plugin reads the data of the shapes,
// volumes and textures nested in a medium this way (a mesh's buffers, a grid's samples and
// to_world, a bitmap's texels), because their classes live in Mitsuba's plugin libraries, not in
// the wheel's headers (mesh.h itself needs struct-jit headers that the wheel lacks).
#pragma once

#include <drjit/tensor.h>
#include <mitsuba/core/object.h>

#include <string>
#include <string_view>
#include <typeinfo>
#include <vector>

namespace mfmi {

class Traversed final : public mitsuba::TraversalCallback {
public:
    /// Collects what `object` reports (traverse() changes nothing).
    explicit Traversed(mitsuba::Object* object) { object->traverse(this); }

    /// The parameter `name` if the object reports it with type T, else null.
    template <typename T>
    const T* value(std::string_view name) const {
        for (const Value& v : values_)
            if (v.name == name && *v.type == typeid(T)) return static_cast<const T*>(v.value);
        return nullptr;
    }

    /// The nested object `name`, or null.
    mitsuba::Object* object(std::string_view name) const {
        for (const auto& [n, o] : objects_)
            if (n == name) return o;
        return nullptr;
    }

protected:
    void put_value(std::string_view name, void* value, uint32_t, const std::type_info& type) override {
        values_.push_back(Value{std::string(name), value, &type});
    }
    void put_object(std::string_view name, mitsuba::Object* object, uint32_t) override {
        objects_.emplace_back(std::string(name), object);
    }

private:
    struct Value {
        std::string name;
        void* value;
        const std::type_info* type;
    };
    std::vector<Value> values_;
    std::vector<std::pair<std::string, mitsuba::Object*>> objects_;
};

}  // namespace mfmi
